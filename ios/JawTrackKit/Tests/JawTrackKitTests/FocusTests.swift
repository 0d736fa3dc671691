import Foundation
import JawTrackCore
@testable import JawTrackKit
import XCTest

/// Focus mode planned on the screen model: the capture plan of an iPhone 15 Pro (nearest focus
/// 20 cm, 1080p with a native 2× crop), the guidance to its distance, the focus locked after a
/// steady run, recording only once locked, and the plan and lens positions in the recording.
/// Frames at depths the fixtures do not have are handed to the controller as the pipeline's
/// reports would be (`show`, internal); the recording itself tracks the fixture frames.
final class FocusTests: XCTestCase {
    private var set: FixtureSet!
    private var camera: FakeCamera!
    private var controller: AppController!
    private var documents: URL!
    private let now = 1_795_600_000.0

    override func setUpWithError() throws {
        set = try FixtureSet.load()
        camera = FakeCamera()
        let formats = [(1920, 1080), (3840, 2160)].map { width, height in
            CameraFormatInfo(
                width: width, height: height, frameRates: [1...60], fullRange420: true, fieldOfViewDegrees: 70,
                nativeZooms: [2]
            )
        }
        camera.device = CameraDevice(model: "iPhone16,1", camera: .backWide, minimumFocusMm: 200, formats: formats)
        documents = try Fixtures.scratch("focus-\(name.filter(\.isLetter))")
        controller = AppController(
            settings: SettingsStore(values: MemoryKeyValueStore(), secrets: MemorySecretStore()),
            camera: camera,
            documents: documents,
            makeTransport: { _, _ in MemoryTransport() },
            clock: { [unowned self] in now },
            deliver: { $0() },
            schedule: { _, _ in }
        )
        XCTAssertEqual(controller.settings.settings.focus, .planned, "the default")
        controller.start(cameraAllowed: true)
    }

    /// A solved body (for the jaws' colours).
    private let body = BodyResult(
        cameraFromBody: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 220, 0, 0, 0, 1], covariance: Array(repeating: 0, count: 36),
        tags: [1, 2], rejectedTags: [], rmsPx: 0.1, blurPx: 1, cellPx: 17
    )

    /// The report of a frame whose markers are `depth` mm away, as the pipeline hands it over.
    private func report(
        depth: Double?, defocused: Bool = false, lens: Double? = nil, adjusting: Bool? = nil, solved: Bool = false
    ) -> FrameReport {
        var report = FrameReport()
        report.result = FrameResult(
            frame: 0, t: 0, exposureS: 0.002, maxilla: solved ? body : nil, mandible: solved ? body : nil,
            maxillaFromMandible: nil, maxillaScanFromMandibleScan: nil, flags: defocused ? ["maxilla:defocused"] : [],
            depthMm: depth, defocused: defocused, lensPosition: lens, overlay: Overlay(tags: [], axes: []),
            detectionMs: 1, poseMs: 1, fps: 60
        )
        report.lensPosition = lens
        report.adjustingFocus = adjusting
        return report
    }

    private func show(_ count: Int, depth: Double?, lens: Double? = nil, adjusting: Bool? = nil) {
        for _ in 0..<count {
            controller.show(report(depth: depth, lens: lens, adjusting: adjusting))
        }
    }

    /// Holds the phone still at the plan's distance until the lock is asked, then answers it.
    private func lock(at lensPosition: Double) {
        let asked = camera.focusLocks.count
        show(FocusLock.steadyFrames, depth: 220)
        XCTAssertEqual(camera.focusLocks.count, asked + 1)
        camera.focusLocks[asked](.success(lensPosition))
        controller.pipeline.queue.sync {}
    }

    private var guidance: CaptureGuidance? { controller.state.guidance }

    func testTheCameraIsSetByThePlanAndThePlanIsShownBeforeRecording() throws {
        let setup = try XCTUnwrap(camera.setups.last)
        XCTAssertEqual(setup.formatIndex, 0, "1080p, at the native 2× crop")
        XCTAssertEqual(setup.plan.zoomFactor, 2)
        XCTAssertEqual(setup.plan.focus, .continuousAutoUntilLocked)
        XCTAssertEqual(camera.starts, 1)
        let plan = try XCTUnwrap(controller.state.plan)
        XCTAssertEqual(plan.distanceMm, 220)
        XCTAssertEqual(plan.minFocusMm, 200)
        XCTAssertTrue(controller.state.showsPlan)
        XCTAssertTrue(controller.state.planLines[0].hasPrefix("Hold the phone about 22 cm away: wide camera, 1920×1080"),
                      controller.state.planLines[0])
        XCTAssertEqual(controller.state.planLines.count, 1 + plan.notes.count, "the phone said its nearest focus: no note")
        XCTAssertNil(guidance, "no frame yet")
    }

    func testThePhoneIsGuidedThereFocusLocksAfterASteadyRunThenItMayRecord() throws {
        controller.show(report(depth: 120))
        XCTAssertEqual(guidance?.kind, .tooClose)
        XCTAssertTrue(guidance?.message.contains("this camera focuses from 20 cm") ?? false, guidance?.message ?? "")
        XCTAssertEqual(controller.state.statusBar(now: now).guidance?.tone, .warning)
        XCTAssertTrue(controller.state.statusBar(now: now).guidance?.text.hasPrefix("Too close: ") ?? false)

        controller.toggleRecording()
        XCTAssertFalse(controller.state.isRecording, "not before focus is locked")
        XCTAssertEqual(controller.state.message, UserMessage(
            title: "Recording", text: "Hold the phone about 22 cm from the markers until focus locks; recording starts once it has."
        ))
        controller.dismissMessage()

        show(FocusLock.steadyFrames - 1, depth: 221)
        XCTAssertEqual(guidance, CaptureGuidance(kind: .holdStill, message: "hold still at about 22 cm while focus locks"))
        XCTAssertEqual(controller.state.statusBar(now: now).guidance,
                       StatusItem(text: "Hold still at about 22 cm while focus locks", tone: .normal))
        XCTAssertTrue(camera.focusLocks.isEmpty, "not steady long enough yet")
        show(1, depth: 221, adjusting: true)
        show(FocusLock.steadyFrames - 1, depth: 219, adjusting: false)
        XCTAssertTrue(camera.focusLocks.isEmpty, "a frame taken while the camera adjusted its focus restarts the run")
        show(1, depth: 120)
        show(FocusLock.steadyFrames - 1, depth: 220)
        XCTAssertTrue(camera.focusLocks.isEmpty, "so does a frame too close")
        show(1, depth: 220)
        XCTAssertEqual(camera.focusLocks.count, 1, "\(FocusLock.steadyFrames) steady frames: the lock is asked for")
        show(30, depth: 220)
        XCTAssertEqual(camera.focusLocks.count, 1, "asked once")
        XCTAssertEqual(guidance?.kind, .holdStill, "until the camera answers")
        controller.toggleRecording()
        XCTAssertFalse(controller.state.isRecording)
        controller.dismissMessage()

        camera.focusLocks[0](.success(0.81))
        controller.pipeline.queue.sync {}
        XCTAssertEqual(controller.state.lockedLensPosition, 0.81)
        controller.show(report(depth: 221, lens: 0.81, solved: true))
        XCTAssertEqual(guidance, CaptureGuidance(kind: .ready, message: "22 cm: in focus"))
        var bar = controller.state.statusBar(now: now)
        XCTAssertEqual(bar.guidance, StatusItem(text: "22 cm: in focus", tone: .good))
        XCTAssertEqual(bar.items[0].tone, .good)
        XCTAssertTrue(bar.notes.isEmpty, "\(bar.notes)")

        controller.show(report(depth: 221, defocused: true, lens: 0.81, solved: true))
        XCTAssertEqual(guidance, CaptureGuidance(kind: .outOfFocus, message: "out of focus: hold the phone about 22 cm away"))
        bar = controller.state.statusBar(now: now)
        XCTAssertEqual(bar.guidance?.tone, .problem)
        XCTAssertEqual(bar.items[0].tone, .warning, "a defocused frame is never shown as good")
        XCTAssertEqual(bar.items[1].tone, .warning)

        controller.show(report(depth: 221, lens: 0.85))
        XCTAssertTrue(controller.state.statusBar(now: now).notes.contains(StatusItem(
            text: "Focus moved (lens at 0.85, locked at 0.81): the focal length changed with it.", tone: .problem
        )))
        controller.show(report(depth: 221, lens: 0.825))
        XCTAssertFalse(controller.state.statusBar(now: now).notes.contains { $0.text.hasPrefix("Focus moved") },
                       "within \(FocusLock.lensTolerance) of the lock")

        controller.toggleRecording()
        XCTAssertTrue(controller.state.isRecording)
        XCTAssertNil(controller.state.message)
        XCTAssertFalse(controller.state.showsPlan, "the plan is shown before recording")
    }

    func testTheRecordingKeepsThePlanTheLockedLensAndEachFramesLens() throws {
        lock(at: 0.81)
        controller.toggleRecording()
        XCTAssertTrue(controller.state.isRecording)
        let lenses: [Double?] = [0.81, 0.83, nil]
        for (i, lens) in lenses.enumerated() {
            camera.play(set.frames[i], time: Double(i) / 60, cameraMatrix: set.cameraMatrix, lensPosition: lens)
        }
        controller.pipeline.queue.sync {}
        XCTAssertEqual(controller.state.recordedFrames, 3)
        XCTAssertEqual(controller.state.guidance?.kind, .tooClose, "the fixtures' markers are 8 cm away")
        controller.toggleRecording()
        controller.pipeline.queue.sync {}
        let files = try XCTUnwrap(controller.state.finishedRecording)
        let lines = try jsonLines(files.poses)
        let header = try XCTUnwrap(lines[0]["recording"] as? [String: Any])
        let capture = try XCTUnwrap(header["capture"] as? [String: Any])
        XCTAssertEqual(capture["distance_mm"] as? Double, 220)
        XCTAssertEqual(capture["lens_position"] as? Double, 0.81)
        XCTAssertEqual(capture["zoom"] as? Double, 2)
        XCTAssertEqual(capture["width"] as? Int, 1920)
        XCTAssertTrue((capture["plan"] as? String)?.hasPrefix("hold the phone about 22 cm away") ?? false)
        XCTAssertEqual((header["settings"] as? [String: Any])?["focus"] as? String, "planned")
        XCTAssertEqual(lines.count, 1 + lenses.count)
        XCTAssertEqual(
            lines.dropFirst().map { $0["lens_position"] as? Double }, [0.81, 0.83, 0.81],
            "each frame's own lens position, else where focus was locked"
        )
    }

    func testStoppingTheCameraNewSettingsOrANewConfigurationClearTheLock() throws {
        lock(at: 0.8)
        XCTAssertEqual(controller.state.lockedLensPosition, 0.8)
        controller.phaseChanged(.background)
        XCTAssertNil(controller.state.lockedLensPosition)
        XCTAssertNil(guidance)
        controller.phaseChanged(.active)
        controller.toggleRecording()
        XCTAssertFalse(controller.state.isRecording, "the new session locks again")
        controller.dismissMessage()

        show(FocusLock.steadyFrames, depth: 220)
        XCTAssertEqual(camera.focusLocks.count, 2)
        controller.phaseChanged(.background)
        camera.focusLocks[1](.success(0.7))
        controller.pipeline.queue.sync {}
        XCTAssertNil(controller.state.lockedLensPosition, "a lock asked for in an earlier session does not count")
        controller.phaseChanged(.active)

        lock(at: 0.79)
        XCTAssertEqual(controller.state.lockedLensPosition, 0.79)
        XCTAssertNil(controller.save(controller.settings.settings))
        XCTAssertNil(controller.state.lockedLensPosition, "new settings")

        lock(at: 0.78)
        controller.settingsOpened()
        controller.settingsClosed()
        XCTAssertEqual(camera.setups.count, 2, "configured anew")
        XCTAssertNil(controller.state.lockedLensPosition)
        lock(at: 0.8)
        XCTAssertEqual(controller.state.lockedLensPosition, 0.8)
    }

    func testAFocusThatCannotLockIsSaidAndNotAskedAgain() throws {
        show(FocusLock.steadyFrames, depth: 220)
        camera.focusLocks[0](.failure(PlatformText.focusLockUnsupported(.backWide)))
        XCTAssertEqual(controller.state.message?.title, "Camera")
        XCTAssertTrue(controller.state.message?.text.hasPrefix(
            "The back wide camera cannot lock its focus. Focus mode Planned records only with the focus locked"
        ) ?? false, controller.state.message?.text ?? "")
        controller.dismissMessage()
        show(3 * FocusLock.steadyFrames, depth: 220)
        XCTAssertEqual(camera.focusLocks.count, 1, "not asked again in this session")
        controller.toggleRecording()
        XCTAssertFalse(controller.state.isRecording)
    }

    func testALensPositionTheLibraryRefusesIsNoLock() throws {
        show(FocusLock.steadyFrames, depth: 220)
        camera.focusLocks[0](.success(1.5))
        controller.pipeline.queue.sync {}
        XCTAssertNil(controller.state.lockedLensPosition)
        XCTAssertTrue(controller.state.message?.text.contains("1.5") ?? false, controller.state.message?.text ?? "")
    }

    func testAPlanThatCannotBeMadeIsTheLibrarysReason() throws {
        let slow = CameraFormatInfo(width: 1920, height: 1080, frameRates: [1...30], fullRange420: true, fieldOfViewDegrees: 70)
        camera.device = CameraDevice(model: "iPhone16,1", camera: .backWide, minimumFocusMm: nil, formats: [slow])
        controller.settingsOpened()
        controller.settingsClosed()
        XCTAssertEqual(camera.setups.count, 1, "not configured")
        XCTAssertEqual(controller.state.message?.title, "Camera")
        XCTAssertTrue(controller.state.message?.text.contains("60 frames/s") ?? false, controller.state.message?.text ?? "")
        XCTAssertNil(controller.state.plan)
        controller.dismissMessage()
        controller.toggleRecording()
        XCTAssertFalse(controller.state.isRecording)
        XCTAssertEqual(controller.state.message?.text, "The camera is not set up for its capture plan yet, so focus cannot lock.")
    }

    func testOtherFocusModesNeedNoLockAndShowNoGuidance() throws {
        var auto = controller.settings.settings
        auto.focus = .auto
        controller.settingsOpened()
        XCTAssertNil(controller.save(auto))
        controller.settingsClosed()
        let setup = try XCTUnwrap(camera.setups.last)
        XCTAssertEqual(setup.plan.zoomFactor, 1)
        XCTAssertEqual(setup.plan.focus, .continuousAuto)
        XCTAssertNil(setup.planner)
        XCTAssertNil(controller.state.plan)
        XCTAssertFalse(controller.state.showsPlan)
        show(FocusLock.steadyFrames, depth: 220)
        XCTAssertNil(guidance)
        XCTAssertTrue(camera.focusLocks.isEmpty)
        controller.show(report(depth: 221, defocused: true, solved: true))
        let bar = controller.state.statusBar(now: now)
        XCTAssertNil(bar.guidance)
        XCTAssertEqual(bar.items[0].tone, .warning)
        XCTAssertTrue(bar.notes.contains(StatusItem(
            text: "The markers are out of focus: this frame gives no jaw pose.", tone: .problem
        )))
        controller.toggleRecording()
        XCTAssertTrue(controller.state.isRecording, "no lock needed")
    }
}
