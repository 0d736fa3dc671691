import Foundation
import JawTrackCore
import JawTrackKit
import XCTest

/// The screen model driven as the app drives it, with a fake camera and the real library.
final class ScreenTests: XCTestCase {
    private var set: FixtureSet!
    private var camera: FakeCamera!
    private var controller: AppController!
    private var documents: URL!
    private var transports: [MemoryTransport] = []
    /// Fulfilled when the link has made and started its transport (on the link's queue).
    private var transportMade: XCTestExpectation?
    private var now = 1_795_600_000.0
    /// Work the controller scheduled (delay, work), run by the test.
    private var scheduled: [(Double, () -> Void)] = []

    override func setUpWithError() throws {
        set = try FixtureSet.load()
        camera = FakeCamera()
        camera.device = set.device()
        documents = try Fixtures.scratch("documents-\(name.filter(\.isLetter))")
        controller = makeController(values: MemoryKeyValueStore())
    }

    private func makeController(values: MemoryKeyValueStore) -> AppController {
        AppController(
            settings: SettingsStore(values: values, secrets: MemorySecretStore()),
            camera: camera,
            documents: documents,
            makeTransport: { [unowned self] _, _ in
                let transport = MemoryTransport()
                transports.append(transport)
                transport.onStart = { [unowned self] in transportMade?.fulfill() }
                return transport
            },
            clock: { [unowned self] in now },
            deliver: { $0() },
            schedule: { [unowned self] delay, work in scheduled.append((delay, work)) }
        )
    }

    /// Plays fixture frames and waits until the screen shows them.
    private func play(_ count: Int, from start: Int = 0) {
        for i in start..<(start + count) {
            camera.play(set.frames[i % set.frames.count], time: Double(i) / 30, cameraMatrix: set.cameraMatrix)
        }
        controller.pipeline.queue.sync {}
    }

    func testWithoutTheCameraPermissionTheScreenSaysWhereToAllowIt() {
        controller.start(cameraAllowed: false)
        XCTAssertEqual(controller.state.message?.title, "Camera")
        XCTAssertTrue(controller.state.message?.text.contains("Privacy & Security") ?? false)
        XCTAssertTrue(camera.configured.isEmpty)
    }

    func testFramesReachTheStatusBarAndTheOverlay() throws {
        controller.start(cameraAllowed: true)
        XCTAssertEqual(camera.configured.count, 1)
        XCTAssertEqual(camera.starts, 1)
        XCTAssertTrue(scheduled.isEmpty, "exposure stays automatic unless asked")
        XCTAssertEqual(controller.state.configurationID, 1)
        play(2)
        let state = controller.state
        XCTAssertTrue(state.status.maxilla.solved)
        XCTAssertTrue(state.status.mandible.solved)
        XCTAssertEqual(state.status.exposure, 0.002)
        let bar = state.statusBar(now: now)
        XCTAssertEqual(bar.items[0].tone, .good)
        XCTAssertTrue(bar.items.contains(StatusItem(text: "1/500 s", tone: .normal)))
        XCTAssertFalse(bar.link.shown)
        let overlay = OverlayGeometry(state.overlay) { ViewPoint(x: $0.x * 390, y: $0.y * 844) }
        let tags = try XCTUnwrap(state.overlay).tags.count
        XCTAssertEqual(overlay.labels.count, tags)
        XCTAssertEqual(overlay.outlines.values.map(\.count).reduce(0, +), tags)
        XCTAssertEqual(overlay.axes.map(\.count), [2, 2, 2])
        for corners in overlay.outlines.values.flatMap({ $0 }) {
            XCTAssertTrue(corners.allSatisfy { (0...390).contains($0.x) && (0...844).contains($0.y) })
        }
    }

    func testBackgroundAndSettingsTakeTheCamera() {
        controller.start(cameraAllowed: true)
        controller.phaseChanged(.background)
        XCTAssertEqual(camera.stops, 1)
        controller.phaseChanged(.active)
        XCTAssertEqual(camera.starts, 2)
        controller.settingsOpened()
        XCTAssertEqual(camera.stops, 2)
        controller.phaseChanged(.active)
        XCTAssertEqual(camera.starts, 2, "not restarted under the settings screen")
        var locked = controller.settings.settings
        locked.exposureLocked = true
        XCTAssertNil(controller.save(locked))
        controller.settingsClosed()
        XCTAssertEqual(camera.configured.count, 2)
        XCTAssertEqual(camera.starts, 3)
        XCTAssertEqual(scheduled.map(\.0), [1], "exposure and white balance locked a second after starting")
        scheduled[0].1()
        XCTAssertEqual(camera.locks, 1)
    }

    func testAnExposureLockOfAnEarlierSessionDoesNotFire() {
        var locked = controller.settings.settings
        locked.exposureLocked = true
        XCTAssertNil(controller.save(locked))
        controller.start(cameraAllowed: true)
        XCTAssertEqual(scheduled.count, 1)
        controller.phaseChanged(.background)
        scheduled[0].1()
        XCTAssertEqual(camera.locks, 0, "the camera stopped before the lock was due")
        controller.phaseChanged(.active)
        camera.lockFailure = "This camera cannot lock its exposure."
        scheduled[1].1()
        XCTAssertEqual(camera.locks, 1)
        XCTAssertEqual(controller.state.message, UserMessage(title: "Camera", text: "This camera cannot lock its exposure."))
    }

    func testACameraThatCannotBeConfiguredIsShown() {
        camera.failure = CameraPlanner.missingCamera(.backTele)
        controller.start(cameraAllowed: true)
        XCTAssertEqual(controller.state.message, UserMessage(title: "Camera", text: "This iPhone has no back telephoto camera."))
        XCTAssertEqual(camera.starts, 0)
    }

    func testABadMarkerFileInDocumentsIsTheLibrarysError() throws {
        try Data("{\"bodies\": 3}".utf8).write(to: documents.appendingPathComponent("marker.json"))
        controller.start(cameraAllowed: true)
        XCTAssertEqual(controller.state.message?.title, "Tracker")
        XCTAssertFalse(controller.state.message?.text.isEmpty ?? true)
        XCTAssertTrue(camera.configured.isEmpty)
    }

    func testACalibratedMarkerFileInDocumentsIsUsed() throws {
        let marker = try Fixtures.directory().appendingPathComponent("marker.json")
        try FileManager.default.copyItem(at: marker, to: documents.appendingPathComponent("marker.json"))
        controller.start(cameraAllowed: true)
        XCTAssertNil(controller.state.message)
        play(1)
        XCTAssertTrue(controller.state.status.mandible.solved)
    }

    func testRecordingThenNamingIt() throws {
        // Focus mode auto: recording needs no focus lock (FocusTests records in focus mode planned).
        var auto = controller.settings.settings
        auto.focus = .auto
        XCTAssertNil(controller.save(auto))
        controller.start(cameraAllowed: true)
        controller.toggleRecording()
        XCTAssertTrue(controller.state.isRecording)
        XCTAssertFalse(controller.state.canOpenSettings)
        play(3)
        XCTAssertEqual(controller.state.recordedFrames, 3)
        XCTAssertTrue(controller.state.statusBar(now: now).items.contains(StatusItem(text: "● REC 3", tone: .recording)))
        controller.toggleRecording()
        controller.pipeline.queue.sync {}
        let files = try XCTUnwrap(controller.state.finishedRecording)
        XCTAssertEqual(controller.state.recordingName, RecordingFiles.defaultName(at: Date(timeIntervalSince1970: now)))
        XCTAssertEqual(AppController.savedText(files), "Saved in Files › On My iPhone › JawTrack.")
        controller.nameRecording(as: "Patient 12 chewing")
        XCTAssertNil(controller.state.finishedRecording)
        XCTAssertTrue(FileManager.default.fileExists(atPath: documents.appendingPathComponent("Patient 12 chewing.jsonl").path))
        controller.toggleRecording()
        controller.toggleRecording()
        controller.pipeline.queue.sync {}
        XCTAssertEqual(controller.state.message?.text, "No frame was recorded.")
    }

    func testTransmittingNeedsAReceiverThenStreamsAndTheLightFollowsTheAcks() throws {
        controller.start(cameraAllowed: true)
        controller.setTransmitting(true)
        XCTAssertFalse(controller.state.isTransmitting)
        XCTAssertEqual(controller.state.message?.title, "Transmit")
        controller.dismissMessage()
        var settings = controller.settings.settings
        settings.receiverHost = "192.168.1.20"
        settings.receiverPort = 5005
        settings.pairingKey = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f"
        XCTAssertNil(controller.save(settings))
        transportMade = expectation(description: "the link connects")
        controller.setTransmitting(true)
        XCTAssertTrue(controller.state.isTransmitting)
        wait(for: [transportMade!], timeout: 5)
        let transport = try XCTUnwrap(transports.last)
        transport.become(.ready)
        play(2)
        transport.queue?.sync {}
        XCTAssertEqual(transport.sent.count, 2)
        XCTAssertFalse(controller.state.statusBar(now: now).link.green)
        transport.become(.failed("network down"))
        XCTAssertEqual(controller.state.linkProblem, "The link failed: network down. Reconnecting in 1 s.")
        XCTAssertTrue(controller.state.statusBar(now: now).notes.contains(StatusItem(
            text: "The link failed: network down. Reconnecting in 1 s.", tone: .problem
        )))
        controller.setTransmitting(false)
        XCTAssertFalse(controller.state.isTransmitting)
        XCTAssertNil(controller.state.linkProblem)
    }

    func testTheBiteCalibrationFlow() throws {
        controller.start(cameraAllowed: true)
        controller.calibrateBite()
        controller.pipeline.queue.sync {}
        XCTAssertFalse(controller.state.isCalibrating)
        XCTAssertEqual(controller.state.message?.title, "Calibration failed")
        for i in 0..<13 {
            camera.play(set.frames[0], time: Double(i) / 30, cameraMatrix: set.cameraMatrix)
        }
        // Held until the state is checked: the step itself is quick enough to finish first.
        controller.pipeline.queue.suspend()
        controller.calibrateBite()
        XCTAssertTrue(controller.state.isCalibrating)
        controller.pipeline.queue.resume()
        controller.pipeline.queue.sync {}
        XCTAssertEqual(controller.state.message?.title, "Bite calibrated")
        XCTAssertTrue(
            controller.state.message?.text.hasPrefix("13 frames averaged over 0.40 s") ?? false,
            controller.state.message?.text ?? ""
        )
    }

    func testBadSettingsAreRefusedWithTheLibrarysMessage() {
        var bad = controller.settings.settings
        bad.fps = 1000
        let text = controller.save(bad)
        XCTAssertNotNil(text)
        XCTAssertTrue(text?.contains("1000") ?? false, text ?? "")
        XCTAssertEqual(controller.settings.settings.fps, defaultAppSettings().fps)
    }

    func testAnExposureLongerThanFourMillisecondsIsAWarning() {
        XCTAssertEqual(StatusBar.exposureText(1.0 / 120), "1/120 s")
        XCTAssertEqual(StatusBar.exposureText(0.033), "33 ms")
        var status = TrackingStatus()
        status.exposure = 1.0 / 120
        status.droppedFrames = 4
        let bar = StatusBar(
            status: status, transmitting: true, light: AckLight(), linkProblem: nil, recording: false,
            recordedFrames: 0, now: 0
        )
        XCTAssertTrue(bar.items.contains(StatusItem(text: "1/120 s", tone: .warning)))
        XCTAssertTrue(bar.notes.contains { $0.text.hasPrefix("4 frames dropped") })
        XCTAssertEqual(bar.link.text, "LINK: no ack")
    }

    func testAJawOnTagsTheCalibrationNeverSawIsSaidInWords() {
        var status = TrackingStatus()
        status.flags = ["mandible:single_tag", "mandible:uncalibrated_tag"]
        let bar = StatusBar(
            status: status, transmitting: false, light: AckLight(), linkProblem: nil, recording: false,
            recordedFrames: 0, now: 0
        )
        XCTAssertEqual(
            bar.notes,
            [
                StatusItem(text: "mandible:single_tag, mandible:uncalibrated_tag", tone: .warning),
                StatusItem(text: "The lower marker rests on tags its calibration left nominal.", tone: .warning),
            ]
        )
        status.flags = ["maxilla:uncalibrated_tag", "mandible:uncalibrated_tag"]
        let both = StatusBar(
            status: status, transmitting: false, light: AckLight(), linkProblem: nil, recording: false,
            recordedFrames: 0, now: 0
        )
        XCTAssertEqual(
            both.notes.dropFirst().map(\.text),
            [
                "The upper marker rests on tags its calibration left nominal.",
                "The lower marker rests on tags its calibration left nominal.",
            ]
        )
        status.flags = ["maxilla:single_tag"]
        let plain = StatusBar(
            status: status, transmitting: false, light: AckLight(), linkProblem: nil, recording: false,
            recordedFrames: 0, now: 0
        )
        XCTAssertFalse(plain.notes.contains { $0.text.contains("calibration left nominal") })
    }
}
