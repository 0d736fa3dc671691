import Foundation
import JawTrackCore
import JawTrackKit
import XCTest

/// A session recorded through the pipeline, read back with the recording schema; the naming
/// and the video decisions.
final class RecordingTests: XCTestCase {
    private var set: FixtureSet!
    private var source: MemoryFrameSource!
    private var pipeline: FramePipeline!
    private var reports: [FrameReport] = []
    private var sinks: [MemoryVideoSink] = []

    override func setUpWithError() throws {
        set = try FixtureSet.load()
        source = MemoryFrameSource()
        pipeline = FramePipeline()
        reports = []
        sinks = []
        pipeline.setReportHandler { [unowned self] in reports.append($0) }
        pipeline.attach(source)
        pipeline.use(tracker: try Tracker(settings: defaultSettings(), markerJson: nil))
        pipeline.use(camera: set.configuration, makeVideo: { [unowned self] url in
            let sink = MemoryVideoSink(url: url)
            sinks.append(sink)
            return sink
        })
    }

    private func request(_ directory: URL, name: String = "session", video: Bool = true) -> RecordingRequest {
        var settings = defaultAppSettings()
        settings.recordVideo = video
        return RecordingRequest(
            directory: directory, baseName: name, settingsJSON: StoredSettings(settings).headerJSON(),
            keyId: "aac4ef0c730c0623", withVideo: video
        )
    }

    private func stop() throws -> RecordingFiles? {
        var outcome: Result<RecordingFiles?, Error>?
        let done = expectation(description: "stopped")
        pipeline.stopRecording { result in
            outcome = result
            done.fulfill()
        }
        wait(for: [done], timeout: 5)
        return try XCTUnwrap(outcome).get()
    }

    func testARecordedSessionReadsBackInTheRecordingSchema() throws {
        let folder = try Fixtures.scratch("recording")
        pipeline.startRecording(request(folder))
        for i in set.frames.indices {
            source.play(set.frames[i], time: Double(i) / 30, cameraMatrix: set.cameraMatrix, native: NSString(string: "sample \(i)"))
        }
        XCTAssertEqual(reports.last?.recordedFrames, UInt64(set.frames.count))
        let files = try XCTUnwrap(try stop())
        XCTAssertEqual(files.name, "session")
        XCTAssertEqual(files.video?.lastPathComponent, "session.mov")
        XCTAssertNil(files.videoProblem)
        XCTAssertEqual(sinks.count, 1)
        XCTAssertEqual(sinks[0].frames, set.frames.count)
        XCTAssertTrue(sinks[0].finished)

        let lines = try jsonLines(files.poses)
        XCTAssertEqual(lines.count, 1 + set.frames.count)
        let header = try XCTUnwrap(lines[0]["recording"] as? [String: Any])
        XCTAssertEqual(header["format"] as? String, "jawtrack-recording")
        XCTAssertEqual(header["device"] as? String, "Linux back wide")
        XCTAssertEqual(header["key_id"] as? String, "aac4ef0c730c0623")
        let intrinsics = try XCTUnwrap(header["intrinsics"] as? [String: Double])
        XCTAssertEqual(intrinsics["fx"], set.intrinsics[0])
        XCTAssertEqual(intrinsics["cx"], set.intrinsics[2])
        XCTAssertNotNil(header["marker"] as? [String: Any])
        XCTAssertEqual((header["settings"] as? [String: Any])?["record_video"] as? Bool, true)
        XCTAssertNil(header["capture"], "no capture plan asked for (FocusTests records one)")
        let sessions = Set(lines.dropFirst().compactMap { $0["session"] as? String })
        XCTAssertEqual(sessions.count, 1, "one session id on every frame")
        for (line, report) in zip(lines.dropFirst(), reports) {
            let result = try XCTUnwrap(report.result)
            XCTAssertEqual(line["frame"] as? Int, Int(result.frame))
            let recorded = try XCTUnwrap((line["mandible"] as? [String: Any])?["camera_from_body"] as? [Double])
            for (a, b) in zip(recorded, try XCTUnwrap(result.mandible).cameraFromBody) {
                XCTAssertEqual(a, b, accuracy: 1e-9)
            }
        }
        // For the Rust side: crates/cli/tests/swift_recording.rs exports it with `jawtrack export`.
        let shared = try Fixtures.output().appendingPathComponent("swift-session.jsonl")
        try? FileManager.default.removeItem(at: shared)
        try FileManager.default.copyItem(at: files.poses, to: shared)
    }

    func testAnAcceptedBiteGoesIntoTheRecording() throws {
        let folder = try Fixtures.scratch("bite")
        pipeline.startRecording(request(folder, video: false))
        // Held still for 0.4 s: the library accepts it as a bite.
        for i in 0..<13 {
            source.play(set.frames[0], time: Double(i) / 30, cameraMatrix: set.cameraMatrix)
        }
        var outcome: Result<IntercuspationResult, Error>?
        let done = expectation(description: "calibrated")
        pipeline.calibrate { result in
            outcome = result
            done.fulfill()
        }
        wait(for: [done], timeout: 5)
        let bite = try XCTUnwrap(outcome).get()
        XCTAssertEqual(bite.frames, 13)
        let files = try XCTUnwrap(try stop())
        let lines = try jsonLines(files.poses)
        XCTAssertEqual(lines.count, 1 + 13 + 1, "the header, the frames, then the bite")
        let recorded = try XCTUnwrap(lines.last?["bite"] as? [String: Any])
        XCTAssertEqual(recorded["frames"] as? Int, 13)
        XCTAssertEqual(recorded["session"] as? String, lines[1]["session"] as? String)
        let rest = try XCTUnwrap(recorded["maxilla_from_mandible"] as? [Double])
        for (a, b) in zip(rest, bite.maxillaFromMandible) {
            XCTAssertEqual(a, b, accuracy: 1e-9)
        }
    }

    func testARecordingNeverOverwritesAndRenamesBothFiles() throws {
        let folder = try Fixtures.scratch("naming")
        for _ in 0..<2 {
            pipeline.startRecording(request(folder, name: "JawTrack 2026-11-25 10.00.00"))
            source.play(set.frames[0], time: Double(reports.count), cameraMatrix: set.cameraMatrix)
            _ = try XCTUnwrap(try stop())
        }
        let names = try FileManager.default.contentsOfDirectory(atPath: folder.path).sorted()
        XCTAssertEqual(names, [
            "JawTrack 2026-11-25 10.00.00 2.jsonl", "JawTrack 2026-11-25 10.00.00 2.mov",
            "JawTrack 2026-11-25 10.00.00.jsonl", "JawTrack 2026-11-25 10.00.00.mov",
        ])
        let first = RecordingFiles(
            poses: folder.appendingPathComponent("JawTrack 2026-11-25 10.00.00.jsonl"),
            video: folder.appendingPathComponent("JawTrack 2026-11-25 10.00.00.mov"),
            videoProblem: nil
        )
        let renamed = try first.renamed(to: "  Patient: A/B  ")
        XCTAssertEqual(renamed.name, "Patient- A-B")
        XCTAssertEqual(renamed.video?.lastPathComponent, "Patient- A-B.mov")
        XCTAssertEqual(try renamed.renamed(to: "   ").name, "Patient- A-B", "a blank name keeps the current one")
        let second = RecordingFiles(
            poses: folder.appendingPathComponent("JawTrack 2026-11-25 10.00.00 2.jsonl"),
            video: nil, videoProblem: nil
        )
        XCTAssertEqual(try second.renamed(to: "Patient- A-B").name, "Patient- A-B 2", "a taken name gets a number")
        XCTAssertEqual(RecordingFiles.cleanedName("..hidden"), "hidden")
    }

    func testTheDefaultNameIsTheDateAndTime() {
        let name = RecordingFiles.defaultName(at: Date(timeIntervalSince1970: 1_795_600_000), timeZone: TimeZone(identifier: "UTC")!)
        XCTAssertEqual(name, "JawTrack 2026-11-25 09.46.40")
    }

    func testNoFrameNoRecordingAndNoVideoWithoutAnEncoder() throws {
        let folder = try Fixtures.scratch("empty")
        pipeline.startRecording(request(folder))
        XCTAssertNil(try stop(), "stopped before any frame: nothing recorded")
        pipeline.use(camera: set.configuration, makeVideo: nil)
        pipeline.startRecording(request(folder))
        source.play(set.frames[0], time: 0, cameraMatrix: set.cameraMatrix)
        let problem = try XCTUnwrap(reports.last?.recordingProblem)
        XCTAssertTrue(problem.contains("turn video recording off"), problem)
        XCTAssertTrue(try FileManager.default.contentsOfDirectory(atPath: folder.path).isEmpty)
    }

    func testAVideoWithNoFrameIsReportedMissing() throws {
        let folder = try Fixtures.scratch("novideo")
        pipeline.startRecording(request(folder))
        sinksNotReady()
        source.play(set.frames[0], time: 0, cameraMatrix: set.cameraMatrix)
        let files = try XCTUnwrap(try stop())
        XCTAssertNil(files.video)
        XCTAssertEqual(files.videoProblem, "No video frame was written.")
    }

    private func sinksNotReady() {
        pipeline.use(camera: set.configuration, makeVideo: { [unowned self] url in
            let sink = MemoryVideoSink(url: url)
            sink.readyForMore = false
            sinks.append(sink)
            return sink
        })
    }

    func testAnUnwritableFolderIsTheRecordersIoError() throws {
        let missing = try Fixtures.scratch("missing").appendingPathComponent("not-there")
        pipeline.startRecording(request(missing, video: false))
        source.play(set.frames[0], time: 0, cameraMatrix: set.cameraMatrix)
        let problem = try XCTUnwrap(reports.last?.recordingProblem)
        XCTAssertTrue(problem.contains("not-there"), problem)
        XCTAssertNotNil(reports.last?.result, "tracking goes on")
    }
}
