import Foundation
import JawTrackCore
import JawTrackKit
import XCTest

/// What the app does for a moving jaw: the readout the tracker is told (device table or
/// calibrated value), each frame's exposure recorded, and the exposure cap lifted only in the
/// dark.
final class MotionTests: XCTestCase {
    private var set: FixtureSet!

    override func setUpWithError() throws {
        set = try FixtureSet.load()
    }

    /// The fixture frames' size, with a sensor whose gain tops out at 3200.
    private var format: CameraFormatInfo {
        CameraFormatInfo(
            width: set.frames[0].width, height: set.frames[0].height, frameRates: [1...60], fullRange420: true,
            fieldOfViewDegrees: 65, maxISO: 3200
        )
    }

    /// That format filmed by `model`.
    private func configuration(model: String, settings: AppSettings = defaultAppSettings()) -> CaptureConfiguration {
        CaptureConfiguration(format: format, plan: CapturePlan(settings), model: model, camera: .backWide)
    }

    func testTheCapStartsAtTwoMillisecondsAndLiftsOnlyWhileTheGainIsAtItsLimit() throws {
        XCTAssertEqual(CapturePlan(defaultAppSettings()).maxExposure, 0.002)
        var none = defaultAppSettings()
        none.maxExposureS = 0
        XCTAssertNil(CapturePlan(none).maxExposure)

        let source = MemoryFrameSource()
        let pipeline = FramePipeline()
        var reports: [FrameReport] = []
        pipeline.setReportHandler { reports.append($0) }
        pipeline.attach(source)
        pipeline.use(tracker: try Tracker(settings: defaultSettings(), markerJson: nil))
        pipeline.use(camera: configuration(model: "iPhone16,2"), makeVideo: nil)
        func play(_ i: Int, iso: Double?) -> Double? {
            source.play(set.frames[i % set.frames.count], time: Double(i) / 30, iso: iso, cameraMatrix: set.cameraMatrix)
            return reports.last?.exposureCap
        }
        XCTAssertNil(play(0, iso: 400), "bright: the cap stays at 2 ms")
        XCTAssertEqual(play(1, iso: 3200), 0.004, "gain at its limit: lifted")
        XCTAssertNil(play(2, iso: 3200), "left alone while automatic exposure settles")
        XCTAssertNil(play(15, iso: 3200))
        XCTAssertEqual(play(16, iso: 3200), 0.008, "still dark half a second later: lifted again")
        XCTAssertNil(play(40, iso: 3200), "never above 4× the setting")
        XCTAssertEqual(play(41, iso: 900), 0.004, "bright again: lowered")
        XCTAssertNil(play(60, iso: nil), "no gain said: unchanged")
        XCTAssertTrue(reports.allSatisfy { $0.problem == nil })
    }

    func testTheRecordingSaysTheReadoutAndEachFramesExposure() throws {
        var settings = defaultSettings()
        settings.readoutS = 0.0051
        let source = MemoryFrameSource()
        let pipeline = FramePipeline()
        var reports: [FrameReport] = []
        pipeline.setReportHandler { reports.append($0) }
        pipeline.attach(source)
        pipeline.use(tracker: try Tracker(settings: settings, markerJson: nil))
        pipeline.use(camera: configuration(model: "iPhone16,2"), makeVideo: nil)
        let folder = try Fixtures.scratch("motion-recording")
        pipeline.startRecording(RecordingRequest(
            directory: folder, baseName: "chew", settingsJSON: StoredSettings(defaultAppSettings()).headerJSON(),
            keyId: nil, withVideo: false
        ))
        for i in set.frames.indices {
            source.play(set.frames[i], time: Double(i) / 30, exposure: 0.0015, cameraMatrix: set.cameraMatrix)
        }
        XCTAssertTrue(try XCTUnwrap(reports.last?.result).maxillaFromMandible != nil, "a still jaw tracks with a readout")
        var outcome: Result<RecordingFiles?, Error>?
        let done = expectation(description: "stopped")
        pipeline.stopRecording { outcome = $0; done.fulfill() }
        wait(for: [done], timeout: 5)
        let files = try XCTUnwrap(try XCTUnwrap(outcome).get())
        let lines = try jsonLines(files.poses)
        let header = try XCTUnwrap(lines[0]["recording"] as? [String: Any])
        XCTAssertEqual(header["readout_s"] as? Double, 0.0051)
        XCTAssertEqual(lines.count, 1 + set.frames.count)
        for line in lines.dropFirst() {
            XCTAssertEqual(line["exposure_s"] as? Double, 0.0015)
        }
    }

    func testTheScreenTellsTheTrackerThePhonesReadoutOrTheCalibratedOne() throws {
        let camera = FakeCamera()
        camera.device = set.device(model: "iPhone16,2", format: format)
        let controller = AppController(
            settings: SettingsStore(values: MemoryKeyValueStore(), secrets: MemorySecretStore()),
            camera: camera,
            documents: try Fixtures.scratch("motion-documents"),
            makeTransport: { _, _ in MemoryTransport() },
            deliver: { $0() },
            schedule: { _, _ in }
        )
        controller.start(cameraAllowed: true)
        let table = try XCTUnwrap(controller.state.readout)
        XCTAssertTrue(table.known)
        XCTAssertEqual(table.readoutS, 0.0051, accuracy: 1e-12)
        XCTAssertTrue(table.source.contains("iPhone 15 Pro Max"), table.source)

        var calibrated = controller.settings.settings
        calibrated.calibratedReadoutS = 0.0062
        XCTAssertNil(controller.save(calibrated))
        XCTAssertEqual(controller.state.readout?.readoutS, 0.0062)
        XCTAssertTrue(controller.state.readout?.source.hasPrefix("calibrated") ?? false)

        for i in 0..<3 {
            camera.play(set.frames[i], time: Double(i) / 30, iso: 3200, cameraMatrix: set.cameraMatrix)
        }
        controller.pipeline.queue.sync {}
        XCTAssertEqual(camera.exposureCaps, [0.004], "the dark room lifted the cap once")

        camera.device = set.device(model: "iPhone14,2", format: format)
        controller.settingsOpened()
        var plain = controller.settings.settings
        plain.calibratedReadoutS = nil
        XCTAssertNil(controller.save(plain))
        controller.settingsClosed()
        let unknown = try XCTUnwrap(controller.state.readout)
        XCTAssertFalse(unknown.known)
        XCTAssertEqual(unknown.readoutS, 0)
        XCTAssertTrue(unknown.source.contains("calibrate-camera"), unknown.source)
    }

    func testTheReadoutFieldTakesMillisecondsAndLetsTheLibraryNameAMistake() {
        var form = SettingsForm(defaultAppSettings())
        XCTAssertEqual(form.readoutText, "")
        form.readoutText = " 5,1 "
        XCTAssertEqual(try XCTUnwrap(form.draft.calibratedReadoutS), 0.0051, accuracy: 1e-12)
        XCTAssertNil(form.problem)
        XCTAssertEqual(form.readoutText, "5.1")
        form.readoutText = "fast"
        XCTAssertTrue(form.problem?.contains("calibrated readout") ?? false, form.problem ?? "no problem")
        form.readoutText = ""
        XCTAssertNil(form.draft.calibratedReadoutS)
        XCTAssertTrue(SettingsForm.exposureLimits.contains { $0.value == defaultAppSettings().maxExposureS })
    }

    func testSettingsStoredBeforeTheMotionSettingsStillLoadWithTheirDefaults() throws {
        var object = try XCTUnwrap(
            JSONSerialization.jsonObject(with: JSONEncoder().encode(StoredSettings(defaultAppSettings()))) as? [String: Any]
        )
        XCTAssertNotNil(object.removeValue(forKey: "maxExposureS"), "the key as stored")
        object.removeValue(forKey: "calibratedReadoutS")
        let old = try JSONDecoder().decode(StoredSettings.self, from: JSONSerialization.data(withJSONObject: object))
        let loaded = try old.applied(to: defaultAppSettings())
        XCTAssertEqual(loaded.maxExposureS, 0.002)
        XCTAssertNil(loaded.calibratedReadoutS)
    }
}
