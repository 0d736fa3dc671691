import Foundation
import JawTrackCore
import JawTrackKit
import XCTest

/// The frame pipeline the app runs, fed with the fixture frames as padded camera buffers.
final class PipelineTests: XCTestCase {
    private var set: FixtureSet!
    private var source: MemoryFrameSource!
    private var pipeline: FramePipeline!
    private var reports: [FrameReport] = []

    override func setUpWithError() throws {
        set = try FixtureSet.load()
        source = MemoryFrameSource()
        pipeline = FramePipeline()
        reports = []
        pipeline.setReportHandler { [unowned self] in reports.append($0) }
        pipeline.attach(source)
        pipeline.use(tracker: try Tracker(settings: defaultSettings(), markerJson: nil))
        pipeline.use(camera: set.configuration, makeVideo: nil)
    }

    /// Frame i at `jawtrack track`'s time for images (30 fps).
    private func play(_ i: Int, layout: PixelLayout = .luma, matrix: [Float]? = nil, byteCount: Int? = nil) {
        source.play(
            set.frames[i], layout: layout, time: Double(i) / 30, cameraMatrix: matrix ?? set.cameraMatrix,
            truncateTo: byteCount
        )
    }

    func testTheFixtureFramesGiveThePosesJawtrackTrackGets() throws {
        XCTAssertEqual(set.frames.count, set.tracked.count)
        XCTAssertGreaterThanOrEqual(set.frames.count, 6)
        for i in set.frames.indices {
            play(i)
        }
        XCTAssertEqual(reports.count, set.frames.count)
        var bodies = 0
        for (report, line) in zip(reports, set.tracked) {
            XCTAssertNil(report.problem)
            XCTAssertFalse(report.intrinsicsEstimated)
            let result = try XCTUnwrap(report.result)
            XCTAssertEqual(result.t, try XCTUnwrap(line["t"] as? Double), accuracy: 1e-15)
            for (name, body) in [("maxilla", result.maxilla), ("mandible", result.mandible)] {
                let expected = line[name] as? [String: Any]
                XCTAssertEqual(body == nil, expected == nil, "\(name) in frame \(result.frame)")
                guard let body, let expected else {
                    continue
                }
                bodies += 1
                XCTAssertEqual(body.tags.map(Int.init), expected["tags"] as? [Int])
                let matrix = try XCTUnwrap(expected["camera_from_body"] as? [Double])
                for (ours, theirs) in zip(body.cameraFromBody, matrix) {
                    XCTAssertEqual(ours, theirs, accuracy: 1e-9, "\(name) in frame \(result.frame)")
                }
            }
            let relative = line["maxilla_from_mandible"] as? [Double]
            XCTAssertEqual(result.maxillaFromMandible == nil, relative == nil)
            for (ours, theirs) in zip(result.maxillaFromMandible ?? [], relative ?? []) {
                XCTAssertEqual(ours, theirs, accuracy: 1e-9)
            }
        }
        XCTAssertGreaterThanOrEqual(bodies, 2 * set.frames.count - 2, "the fixture frames show both jaws")
    }

    func testBgraFramesAreTrackedThroughTheLibrarysConversion() throws {
        play(0, layout: .bgra)
        let bgra = try XCTUnwrap(reports.last?.result)
        pipeline.use(tracker: try Tracker(settings: defaultSettings(), markerJson: nil))
        play(0)
        let luma = try XCTUnwrap(reports.last?.result)
        let a = try XCTUnwrap(bgra.maxillaFromMandible)
        let b = try XCTUnwrap(luma.maxillaFromMandible)
        for index in [3, 7, 11] {
            XCTAssertEqual(a[index], b[index], accuracy: 0.01, "BGRA (B = G = R = Y) places the jaw as luma does")
        }
    }

    func testAShortBufferGetsTheLibrarysError() throws {
        let image = set.frames[0]
        play(0, byteCount: (image.width + 64) * (image.height - 1))
        let report = try XCTUnwrap(reports.last)
        XCTAssertNil(report.result)
        let problem = try XCTUnwrap(report.problem)
        XCTAssertTrue(problem.contains("the buffer holds"), problem)
        XCTAssertTrue(problem.contains("bytes per row needs"), problem)
    }

    func testBadIntrinsicsGetTheLibrarysError() throws {
        play(0, matrix: [0, 0, 0, 0, 1500, 0, 960, 540, 1])
        let problem = try XCTUnwrap(reports.last?.problem)
        XCTAssertNil(reports.last?.result)
        XCTAssertTrue(problem.lowercased().contains("fx"), problem)
        play(1, matrix: [1500, 0, 0])
        XCTAssertTrue(try XCTUnwrap(reports.last?.problem).contains("9 numbers"))
    }

    func testAFrameWithoutAMatrixUsesTheFieldOfViewAndSaysSo() throws {
        source.play(set.frames[0], time: 0, cameraMatrix: nil)
        XCTAssertTrue(try XCTUnwrap(reports.last).intrinsicsEstimated)
        XCTAssertNil(reports.last?.problem)
    }

    func testIntrinsicsAreScaledToTheDeliveredFrame() throws {
        let format = CameraFormatInfo(width: 3840, height: 2160, frameRates: [1...30], fullRange420: true, fieldOfViewDegrees: 65)
        let configuration = CaptureConfiguration(format: format, plan: CapturePlan(defaultAppSettings()), model: "m", camera: .backWide)
        let matrix: [Float] = [3000, 0, 0, 0, 3000, 0, 1920, 1080, 1]
        let (intrinsics, estimated) = try CameraPlanner.intrinsics(
            cameraMatrix: matrix, configuration: configuration, width: 1920, height: 1080
        )
        XCTAssertFalse(estimated)
        XCTAssertEqual(intrinsics.fx, 1500)
        XCTAssertEqual(intrinsics.cx, 959.5)
        XCTAssertEqual(intrinsics.cy, 539.5)
    }

    func testLateAndStaleFramesAreCountedAsDropped() throws {
        source.play(set.frames[0], time: 1, cameraMatrix: set.cameraMatrix)
        source.play(set.frames[1], time: 1 + 1.0 / 30, cameraMatrix: set.cameraMatrix)
        XCTAssertEqual(reports.last?.droppedFrames, 0)
        source.play(set.frames[2], time: 1 + 4.0 / 30, cameraMatrix: set.cameraMatrix)
        XCTAssertEqual(reports.last?.droppedFrames, 2, "two frames missing between 1/30 and 4/30")
        let count = reports.count
        source.play(set.frames[3], time: 1 + 4.0 / 30, cameraMatrix: set.cameraMatrix)
        XCTAssertEqual(reports.count, count, "a frame no later than the last one is not tracked")
        source.play(set.frames[4], time: 1 + 5.0 / 30, cameraMatrix: set.cameraMatrix)
        XCTAssertEqual(reports.last?.droppedFrames, 3)
        XCTAssertEqual(reports.last?.exposure, 0.002)
    }

    func testNothingIsTrackedBeforeTheCameraIsConfigured() throws {
        pipeline.use(camera: nil, makeVideo: nil)
        play(0)
        XCTAssertTrue(reports.isEmpty)
    }

    func testTheBiteCalibrationNeedsAHeldBiteThenAveragesIt() throws {
        let early = expectation(description: "refused")
        pipeline.calibrate { result in
            guard case .failure(let error) = result, case JawTrackError.NotEnoughFrames(let needed, let got, _) = error else {
                return XCTFail("expected NotEnoughFrames, got \(result)")
            }
            XCTAssertEqual(needed, 8)
            XCTAssertEqual(got, 0)
            XCTAssertFalse(userText(error).isEmpty)
            early.fulfill()
        }
        wait(for: [early], timeout: 5)
        // Two frames are not a held bite (the library's rule; the moving jaw is refused in
        // crates/ffi/tests/python and crates/tracker/src/bite.rs, this fixture being still).
        for i in 0..<2 {
            source.play(set.frames[0], time: Double(i) / 30, cameraMatrix: set.cameraMatrix)
        }
        let brief = expectation(description: "brief")
        pipeline.calibrate { result in
            guard case .failure(let error) = result, case JawTrackError.NotEnoughFrames(_, let got, _) = error else {
                return XCTFail("expected NotEnoughFrames, got \(result)")
            }
            XCTAssertEqual(got, 2)
            brief.fulfill()
        }
        wait(for: [brief], timeout: 5)
        for i in 2..<30 {
            source.play(set.frames[0], time: Double(i) / 30, cameraMatrix: set.cameraMatrix)
        }
        let done = expectation(description: "calibrated")
        pipeline.calibrate { result in
            guard case .success(let bite) = result else {
                return XCTFail("\(result)")
            }
            XCTAssertGreaterThanOrEqual(bite.frames, 8)
            XCTAssertLessThan(bite.spreadMm, 0.01, "the same frame over and over: no spread")
            XCTAssertTrue(AppController.biteText(bite).contains("frames averaged"))
            done.fulfill()
        }
        wait(for: [done], timeout: 5)
    }

    func testNewTrackerSettingsAreValidatedByTheLibrary() throws {
        var bad = defaultSettings()
        bad.decimate = 5
        let refused = expectation(description: "refused")
        pipeline.update(trackerSettings: bad) { error in
            XCTAssertTrue(userText(error!).contains("decimation must be"), userText(error!))
            refused.fulfill()
        }
        var good = defaultSettings()
        good.decimate = 1
        let accepted = expectation(description: "accepted")
        pipeline.update(trackerSettings: good) { error in
            XCTAssertNil(error)
            accepted.fulfill()
        }
        wait(for: [refused, accepted], timeout: 5)
    }
}
