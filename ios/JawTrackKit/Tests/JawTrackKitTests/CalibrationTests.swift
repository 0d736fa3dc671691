import Foundation
import JawTrackCore
import JawTrackKit
import XCTest

/// The marker calibration screen driven as the app drives it, on the hinge fixture (the lower
/// jaw turns by 18° over its five frames; the upper one holds still), with the real library.
final class CalibrationTests: XCTestCase {
    private var set: FixtureSet!
    private var camera: FakeCamera!
    private var controller: AppController!
    private var documents: URL!
    private var calibrationQueue: DispatchQueue!
    private var time = 0.0

    override func setUpWithError() throws {
        set = try FixtureSet.load("hinge-1080p")
        camera = FakeCamera()
        camera.device = set.device()
        documents = try Fixtures.scratch("calibration-\(name.filter(\.isLetter))")
        calibrationQueue = DispatchQueue(label: "test.calibration")
        controller = AppController(
            settings: SettingsStore(values: MemoryKeyValueStore(), secrets: MemorySecretStore()),
            camera: camera,
            documents: documents,
            calibrationQueue: calibrationQueue,
            makeTransport: { _, _ in MemoryTransport() },
            deliver: { $0() },
            schedule: { _, _ in }
        )
        controller.start(cameraAllowed: true)
    }

    private var screen: CalibrationScreen { controller.markerCalibration.state }

    /// Plays fixture frames (at increasing times) and waits until the screens show them.
    private func play(_ indices: [Int]) {
        for i in indices {
            camera.play(set.frames[i], time: time, cameraMatrix: set.cameraMatrix)
            time += 1.0 / 30
        }
        controller.pipeline.queue.sync {}
    }

    /// Opens the screen and plays the fixture's frames once.
    private func collect() {
        controller.openMarkerCalibration()
        controller.pipeline.queue.sync {}
        play(Array(set.frames.indices))
    }

    /// Solves and waits for the result (held until the solving state is checked).
    private func solve() {
        calibrationQueue.suspend()
        controller.markerCalibration.solve()
        XCTAssertEqual(screen.phase, .solving)
        calibrationQueue.resume()
        calibrationQueue.sync {}
    }

    func testViewsAreCollectedSolvedSavedAndTracked() throws {
        var changes: [CalibrationScreen] = []
        controller.markerCalibration.onChange = { changes.append($0) }
        XCTAssertFalse(screen.isOpen)
        controller.openMarkerCalibration()
        XCTAssertEqual(screen.phase, .collecting)
        XCTAssertEqual(screen.readiness, "Show the markers to the camera.")
        controller.pipeline.queue.sync {}
        play([0])
        XCTAssertEqual(screen.views, 1)
        XCTAssertEqual(screen.hint, "View added: keep turning.")
        XCTAssertFalse(screen.canSolve)
        XCTAssertEqual(screen.readiness, "Not ready: a tag needs 3 views, each from an angle at least 5° from the others.")
        XCTAssertEqual(screen.bodyLines.count, 2)
        XCTAssertTrue(screen.bodyLines[0].hasPrefix("Upper marker: 1 view, 0 of 12 tags ready; still needing views: tags 0, 1, 2,"), screen.bodyLines[0])
        play([0])
        XCTAssertEqual(screen.views, 1, "the same frame again is no new view")
        XCTAssertEqual(screen.hint, "Seen from here already: turn the marker further.")
        play([1, 2, 3, 4])
        XCTAssertGreaterThanOrEqual(screen.views, 3)
        XCTAssertTrue(screen.canSolve)
        XCTAssertTrue(screen.readiness.hasPrefix("Ready to solve. Tags still needing views"), screen.readiness)
        XCTAssertTrue(screen.bodyLines[0].hasPrefix("Upper marker: 1 view, 0 of 12 tags ready"), screen.bodyLines[0])
        let lower = screen.bodyLines[1]
        XCTAssertTrue(lower.hasPrefix("Lower marker: "), lower)
        XCTAssertFalse(lower.contains(" 0 of 12 tags ready"), lower)
        XCTAssertFalse(lower.contains("tags 12, 13, 14, 15, 16,"), "the lower tags seen thrice are ready: \(lower)")
        XCTAssertGreaterThan(changes.count, 5)

        solve()
        XCTAssertEqual(screen.phase, .solved)
        XCTAssertTrue(screen.canSave)
        XCTAssertEqual(screen.summary.count, 2)
        XCTAssertTrue(screen.summary[0].hasPrefix("Upper marker: 1 view; error "), screen.summary[0])
        XCTAssertTrue(screen.summary[0].hasSuffix("0 of 12 tags calibrated."), screen.summary[0])
        XCTAssertTrue(screen.summary[1].hasPrefix("Lower marker: "), screen.summary[1])
        XCTAssertEqual(screen.rows.count, 24)
        let calibrated = screen.rows.filter(\.calibrated)
        XCTAssertFalse(calibrated.isEmpty)
        XCTAssertTrue(calibrated.allSatisfy { $0.body == "Lower" && $0.error.contains(" → ") })
        let nominal = try XCTUnwrap(screen.rows.first { $0.id == 0 })
        XCTAssertEqual(nominal.text, "Upper tag 0: 1 view, left nominal")
        XCTAssertEqual([nominal.shift, nominal.turn, nominal.error], ["—", "—", "left nominal"])
        XCTAssertTrue(screen.findings.contains { $0.hasPrefix("Tag 3 was seen in 0 usable view(s), too few to calibrate") }, "\(screen.findings)")
        XCTAssertTrue(screen.findings.allSatisfy { $0.hasSuffix(".") })
        XCTAssertNil(screen.warning)

        controller.markerCalibration.save()
        XCTAssertEqual(screen.phase, .saved)
        XCTAssertEqual(screen.message?.title, "Marker saved")
        XCTAssertTrue(screen.message?.text.contains("calibrate the bite again") ?? false)
        let saved = try JSONSerialization.jsonObject(
            with: Data(contentsOf: documents.appendingPathComponent("marker.json"))
        ) as? [String: Any]
        let bodies = try XCTUnwrap(saved?["bodies"] as? [[String: Any]])
        let statuses = bodies.flatMap { ($0["tags"] as? [[String: Any]]) ?? [] }.map {
            (($0["id"] as? Int) ?? -1, (($0["calibration"] as? [String: Any])?["status"] as? String) ?? "")
        }
        XCTAssertEqual(statuses.filter { $0.1 == "calibrated" }.map(\.0), calibrated.map { Int($0.id) })
        XCTAssertEqual(statuses.filter { $0.1 == "nominal" }.count, 24 - calibrated.count)

        // Tracking uses the file at once: the upper jaw now rests on tags it left nominal.
        play([0])
        XCTAssertTrue(controller.state.status.flags.contains("maxilla:uncalibrated_tag"), "\(controller.state.status.flags)")
        let views = screen.views
        play([1, 2])
        XCTAssertEqual(screen.views, views, "no more views once saved")
        controller.markerCalibration.close()
        XCTAssertFalse(screen.isOpen)
        // Calibrating again starts afresh from the nominal marker of the file just saved.
        controller.openMarkerCalibration()
        controller.pipeline.queue.sync {}
        play([0])
        XCTAssertEqual(screen.views, 1)
        XCTAssertTrue(screen.bodyLines[1].hasPrefix("Lower marker: 1 view, 0 of 12 tags ready"), screen.bodyLines[1])
    }

    func testAnExistingMarkerFileIsReplacedOnlyWhenTheUserSaysSo() throws {
        collect()
        solve()
        let url = documents.appendingPathComponent("marker.json")
        try Data("precious".utf8).write(to: url)
        controller.markerCalibration.save()
        XCTAssertTrue(screen.confirmReplace)
        XCTAssertEqual(screen.phase, .solved)
        XCTAssertEqual(try String(contentsOf: url, encoding: .utf8), "precious")
        controller.markerCalibration.keepExistingFile()
        XCTAssertFalse(screen.confirmReplace)
        XCTAssertEqual(try String(contentsOf: url, encoding: .utf8), "precious")
        controller.markerCalibration.save(replacing: true)
        XCTAssertEqual(screen.phase, .saved)
        XCTAssertTrue(try String(contentsOf: url, encoding: .utf8).contains("\"calibration\""))
        XCTAssertEqual(try FileManager.default.contentsOfDirectory(atPath: documents.path), ["marker.json"], "no temporary file")
    }

    func testSolvingTooEarlyShowsTheLibrarysReasonAndCollectsOn() {
        controller.openMarkerCalibration()
        controller.pipeline.queue.sync {}
        play([0])
        solve()
        XCTAssertEqual(screen.phase, .collecting)
        XCTAssertEqual(screen.message?.title, "Not solved")
        XCTAssertTrue(screen.message?.text.contains("no tag has been seen in 3 views yet") ?? false, screen.message?.text ?? "")
        controller.markerCalibration.dismissMessage()
        XCTAssertNil(screen.message)
        play([2, 3])
        XCTAssertEqual(screen.views, 3, "views are still collected after the refusal")
        controller.markerCalibration.save()
        XCTAssertFalse(FileManager.default.fileExists(atPath: documents.appendingPathComponent("marker.json").path))
    }

    func testAddingViewsAfterASolveAndStartingOver() {
        collect()
        let views = screen.views
        solve()
        controller.markerCalibration.addViews()
        XCTAssertEqual(screen.phase, .collecting)
        XCTAssertTrue(screen.rows.isEmpty)
        XCTAssertEqual(screen.views, views)
        controller.markerCalibration.startOver()
        XCTAssertEqual(screen.views, 0)
        XCTAssertFalse(screen.canSolve)
        play([0])
        XCTAssertEqual(screen.views, 1, "fed again after starting over")
    }

    func testTheMarkerIsNotCalibratedWhileRecording() {
        // Focus mode auto: recording needs no focus lock (FocusTests records in focus mode planned).
        var auto = controller.settings.settings
        auto.focus = .auto
        controller.settingsOpened()
        XCTAssertNil(controller.save(auto))
        controller.settingsClosed()
        controller.toggleRecording()
        XCTAssertTrue(controller.state.isRecording)
        XCTAssertFalse(controller.state.canCalibrateMarker)
        controller.openMarkerCalibration()
        XCTAssertFalse(screen.isOpen)
        XCTAssertEqual(controller.state.message?.title, "Marker calibration")
        controller.toggleRecording()
        controller.pipeline.queue.sync {}
    }

    func testTheProgressAndTheResultInWords() {
        let body = { (name: String, views: UInt32, last: ViewOutcome?, needs: [UInt32]) in
            BodyViews(
                body: name, views: views, last: last, lastTags: 2, tagsReady: 12 - UInt32(needs.count), tagsTotal: 12,
                needsViews: needs
            )
        }
        var screen = CalibrationScreen()
        screen.show(CalibrationProgress(
            views: 4, minViews: 3, minTurnDeg: 5, added: false, note: "", bodies: [
                body("maxilla", 4, .tooFewTags, []), body("mandible", 1, .tooFewTags, [12, 20]),
            ], tags: [], needsViews: [12, 20], canSolve: true, complete: false
        ))
        XCTAssertEqual(screen.bodyLines, [
            "Upper marker: 4 views, 12 of 12 tags ready.",
            "Lower marker: 1 view, 10 of 12 tags ready; still needing views: tags 12, 20.",
        ])
        XCTAssertEqual(screen.hint, "Turn a marker so that two faces or more face the camera at once.")
        screen.show(CalibrationProgress(
            views: 4, minViews: 3, minTurnDeg: 5, added: false, note: "", bodies: [body("maxilla", 4, .notTracked, [])], tags: [],
            needsViews: [], canSolve: true, complete: true
        ))
        XCTAssertEqual(screen.hint, "A marker shows tags but is not tracked: hold it steadier, in good light.")
        XCTAssertEqual(screen.readiness, "Every tag has enough views: ready to solve.")

        let tag = TagCalibrationResult(
            id: 13, body: "mandible", face: 1, views: 16, calibrated: true, shiftXMm: 0.3, shiftYMm: -0.204,
            turnDeg: 1.46, rmsBeforePx: 5.45, rmsAfterPx: 0.004
        )
        let row = CalibrationRow(tag)
        XCTAssertEqual([row.body, row.tag, row.views, row.shift, row.turn, row.error], ["Lower", "13", "16", "+0.30, -0.20", "+1.5", "5.45 → 0.00"])
        XCTAssertEqual(row.text, "Lower tag 13: 16 views, shifted +0.30, -0.20 mm, turned +1.5°, error 5.45 → 0.00 px")
        screen.show(
            MarkerCalibrationResult(
                bodies: [BodyCalibrationResult(body: "mandible", views: 16, rmsBeforePx: 1.234, rmsAfterPx: 0.2, tagsCalibrated: 1, tagsTotal: 12)],
                tags: [tag], findings: ["tag 5 is glued a half turn from upright (seen from outside); corrected"],
                focalWarning: "the camera's focal length looks wrong: over 9 views", markerJson: "{}"
            ),
            bodiesSeen: ["maxilla", "mandible"]
        )
        XCTAssertEqual(screen.summary, [
            "Lower marker: 16 views; error 1.23 px before, 0.20 px after; 1 of 12 tags calibrated.",
            "Upper marker: never seen; it keeps the placement it had.",
        ])
        XCTAssertEqual(screen.findings, ["Tag 5 is glued a half turn from upright (seen from outside); corrected."])
        XCTAssertEqual(screen.warning, "The camera's focal length looks wrong: over 9 views.")
    }
}
