import Foundation
import JawTrackCore

/// The camera as the app drives it (AVFoundation's capture session in the app). It is also the
/// frame source. Calls may block, so the camera does its work on its own queue.
public protocol CameraControl: FrameSource {
    /// Describes `camera` as it is before being configured (the phone's model, the nearest
    /// distance the lens focuses at, the formats); `completion` gets it, or why not (no such
    /// camera). The capture plan and the format are decided from it (`CaptureSetup`).
    func describe(_ camera: Camera, completion: @escaping (Result<CameraDevice, Error>) -> Void)
    /// Sets the camera up as `setup` says (its device's camera, the format at
    /// `setup.formatIndex`, `setup.plan`); `completion` gets how to make a movie writer for that
    /// format (nil when it offers none), or why the camera could not be set up.
    func configure(_ setup: CaptureSetup, completion: @escaping (Result<VideoSinkFactory?, Error>) -> Void)
    /// Starts the frames. A plan whose focus is `continuousAutoUntilLocked` focuses
    /// continuously again (a lock of an earlier session is let go).
    func start()
    /// Locks the focus where the lens is now; `completion` gets the lens position it locked at
    /// (0 near – 1 far) once the lens is locked, or why it could not lock.
    func lockFocus(completion: @escaping (Result<Double, Error>) -> Void)
    /// Locks exposure and white balance where they are now; `onProblem` gets what could not be done.
    func lockExposureAndWhiteBalance(onProblem: @escaping (String) -> Void)
    /// Caps the exposure automatic exposure may choose (s; nil: the camera's own limit), within
    /// what the format allows.
    func limitExposure(to seconds: Double?)
    func stop()
}

/// The app's lifecycle, as the screen sees it.
public enum AppPhase {
    case active, inactive, background
}

/// Everything the screen shows.
public struct ScreenState {
    public var status = TrackingStatus()
    /// The last result's overlay (nil: draw nothing).
    public var overlay: Overlay?
    public var isRecording = false
    public var recordedFrames: UInt64 = 0
    public var isTransmitting = false
    public var light = AckLight()
    public var linkProblem: String?
    public var isCalibrating = false
    /// Bumped when the camera is configured anew (the preview re-reads its connection).
    public var configurationID = 0
    /// The alert on screen, if any.
    public var message: UserMessage?
    /// A stopped recording waiting for its name.
    public var finishedRecording: RecordingFiles?
    /// The name field's starting text.
    public var recordingName = ""
    /// The rolling-shutter readout the tracker is told and where it comes from (nil until the
    /// camera is configured).
    public var readout: ReadoutChoice?
    /// The capture plan the camera is set by (focus mode planned; nil otherwise).
    public var plan: PlanChoice?
    /// The last frame's guidance to the plan's distance and focus (focus mode planned).
    public var guidance: CaptureGuidance?
    /// Where focus was locked for this session (focus mode planned; nil: not yet).
    public var lockedLensPosition: Double?

    /// The status bar at `now`.
    public func statusBar(now: Double) -> StatusBar {
        StatusBar(
            status: status, transmitting: isTransmitting, light: light, linkProblem: linkProblem,
            recording: isRecording, recordedFrames: recordedFrames, now: now, guidance: guidance
        )
    }

    /// Whether the plan is shown: before recording, while there is one.
    public var showsPlan: Bool { plan != nil && !isRecording }
    /// The plan in words: its summary, then each of its notes once (figures assumed, a target
    /// out of reach).
    public var planLines: [String] {
        guard let plan else {
            return []
        }
        var lines = [StatusBar.sentence(plan.summary)]
        for note in plan.notes.map(StatusBar.sentence) where !lines.contains(note) {
            lines.append(note)
        }
        return lines
    }

    /// Settings are locked while recording (a recording has one set of settings).
    public var canOpenSettings: Bool { !isRecording }
    /// The marker is calibrated only while not recording (a recording has one marker file).
    public var canCalibrateMarker: Bool { !isRecording }
}

/// The screen's logic: wires camera, pipeline, settings, recording, link, the bite calibration
/// and the marker calibration's screen (`markerCalibration`), and turns every outcome into state
/// or a message. Call it on one thread (the main thread in the app); results from the pipeline
/// come back through `deliver`. `onChange` gets the state after every change.
public final class AppController {
    public private(set) var state = ScreenState() {
        didSet { onChange?(state) }
    }
    public var onChange: ((ScreenState) -> Void)?
    public let settings: SettingsStore
    public let pipeline: FramePipeline
    /// The marker calibration screen's logic; a marker it saves is tracked at once.
    public let markerCalibration: CalibrationController

    private let camera: CameraControl
    private let documents: URL?
    private let makeTransport: TransportFactory
    private let deliver: (@escaping () -> Void) -> Void
    private let schedule: (Double, @escaping () -> Void) -> Void
    private let clock: () -> Double
    /// Bumped whenever the camera starts, stops or is configured: a pending exposure lock of an
    /// earlier session must not fire in a later one (whose settings may not want it).
    private var cameraGeneration = 0
    /// Bumped whenever the focus lock is cleared: a lock asked for before must not count after.
    private var focusGeneration = 0
    /// Bumped whenever the camera is described and configured anew: the answers of an earlier
    /// configuration are dropped.
    private var configurationGeneration = 0
    private var tracker: Tracker?
    /// The camera as last configured: its model and lens key the readout table.
    private var configuration: CaptureConfiguration?
    /// The capture plan of the camera as configured (focus mode planned).
    private var planner: CapturePlanner?
    /// This session's focus lock (focus mode planned; nil otherwise).
    private var focusLock: FocusLock?
    private var linkKeyId: String?
    private var started = false
    private var cameraReady = false
    private var settingsOpen = false
    private var link: LinkSession?

    /// `documents`: where recordings go and a calibrated `marker.json` is looked for (and saved
    /// by the marker calibration). `deliver` runs a closure on the controller's thread
    /// (`DispatchQueue.main.async` in the app), `schedule` after a delay in seconds on that
    /// thread; `calibrationQueue` is where marker calibrations are solved.
    public init(
        settings: SettingsStore,
        camera: CameraControl,
        documents: URL?,
        pipeline: FramePipeline = FramePipeline(),
        calibrationQueue: DispatchQueue = DispatchQueue(label: "org.jawtrack.calibration", qos: .userInitiated),
        makeTransport: @escaping TransportFactory,
        clock: @escaping () -> Double = { Date().timeIntervalSince1970 },
        deliver: @escaping (@escaping () -> Void) -> Void = { DispatchQueue.main.async(execute: $0) },
        schedule: @escaping (Double, @escaping () -> Void) -> Void = { delay, work in
            DispatchQueue.main.asyncAfter(deadline: .now() + delay, execute: work)
        }
    ) {
        self.settings = settings
        self.camera = camera
        self.documents = documents
        self.pipeline = pipeline
        self.makeTransport = makeTransport
        self.clock = clock
        self.deliver = deliver
        self.schedule = schedule
        markerCalibration = CalibrationController(
            pipeline: pipeline, documents: documents, queue: calibrationQueue, deliver: deliver
        )
        markerCalibration.useSavedMarker = { [weak self] in try self?.reloadMarker() }
        pipeline.setReportHandler { [weak self] report in
            deliver { self?.show(report) }
        }
        pipeline.attach(camera)
    }

    // MARK: Camera

    /// First appearance, once the camera permission is known.
    public func start(cameraAllowed: Bool) {
        guard !started else {
            return
        }
        started = true
        if let problem = settings.loadProblem {
            state.message = UserMessage(title: "Settings", text: problem)
        }
        guard cameraAllowed else {
            state.message = UserMessage(
                title: "Camera",
                text: "JawTrack needs the camera to track the markers. Allow it in Settings › Privacy & Security › Camera."
            )
            return
        }
        startCamera()
    }

    public func phaseChanged(_ phase: AppPhase) {
        switch phase {
        case .background:
            stopCamera()
        case .active:
            if cameraReady, !settingsOpen {
                startSession()
            }
        case .inactive:
            break
        }
    }

    /// The settings screen takes the camera (for the QR scanner).
    public func settingsOpened() {
        settingsOpen = true
        stopCamera()
    }

    private func stopCamera() {
        cameraGeneration += 1
        clearFocusLock()
        camera.stop()
    }

    /// Back from the settings screen: the camera again, with the settings as saved.
    public func settingsClosed() {
        settingsOpen = false
        startCamera()
    }

    private func startCamera() {
        if tracker == nil {
            do {
                let newTracker = try Tracker(settings: trackerSettings(settings.settings), markerJson: try markerJSON())
                tracker = newTracker
                pipeline.use(tracker: newTracker)
            } catch {
                state.message = UserMessage(title: "Tracker", text: userText(error))
                return
            }
        }
        cameraReady = false
        cameraGeneration += 1
        configurationGeneration += 1
        planner = nil
        clearFocusLock()
        state.plan = nil
        let generation = configurationGeneration
        let current = settings.settings
        camera.describe(current.camera) { [weak self] result in
            self?.deliver { self?.cameraDescribed(result, settings: current, generation: generation) }
        }
    }

    /// The camera described: the plan and format decided (`CaptureSetup`, with the marker the
    /// tracker uses), then the camera configured with them.
    private func cameraDescribed(_ result: Result<CameraDevice, Error>, settings current: AppSettings, generation: Int) {
        guard generation == configurationGeneration else {
            return
        }
        let setup: CaptureSetup
        do {
            setup = try CaptureSetup(device: result.get(), settings: current, markerJSON: tracker?.markerJson())
        } catch {
            state.message = UserMessage(title: "Camera", text: userText(error))
            return
        }
        camera.configure(setup) { [weak self] result in
            self?.deliver { self?.cameraConfigured(result, setup: setup, generation: generation) }
        }
    }

    private func cameraConfigured(_ result: Result<VideoSinkFactory?, Error>, setup: CaptureSetup, generation: Int) {
        guard generation == configurationGeneration else {
            return
        }
        switch result {
        case .success(let makeVideo):
            configuration = setup.configuration
            planner = setup.planner
            state.plan = setup.choice
            updateTrackerSettings(settings.settings)
            pipeline.use(camera: setup.configuration, makeVideo: makeVideo)
            cameraReady = true
            state.configurationID += 1
            if !settingsOpen {
                startSession()
            }
        case .failure(let error):
            state.message = UserMessage(title: "Camera", text: userText(error))
        }
    }

    /// A new session, new settings or a new configuration: focus is locked anew (focus mode
    /// planned), and an answer to a lock asked for before is dropped.
    private func clearFocusLock() {
        focusGeneration += 1
        focusLock = planner.map(FocusLock.init(planner:))
        state.guidance = nil
        state.lockedLensPosition = nil
        state.status.focusMoved = nil
        pipeline.focusLocked(at: nil)
    }

    /// Asks the camera to lock its focus; the answer counts only in the session that asked.
    private func lockFocus() {
        let generation = focusGeneration
        camera.lockFocus { [weak self] result in
            self?.deliver { self?.focusLocked(result, generation: generation) }
        }
    }

    /// The camera's answer: the lens position goes to the tracker (the library checks it), then
    /// the lock counts.
    private func focusLocked(_ result: Result<Double, Error>, generation: Int) {
        guard generation == focusGeneration, focusLock != nil else {
            return
        }
        switch result {
        case .success(let lensPosition):
            pipeline.focusLocked(at: lensPosition) { [weak self] error in
                self?.deliver { self?.focusTaken(at: lensPosition, error: error, generation: generation) }
            }
        case .failure(let error):
            focusLock?.failed()
            state.message = UserMessage(title: "Camera", text: PlatformText.focusNotLocked(error))
        }
    }

    private func focusTaken(at lensPosition: Double, error: Error?, generation: Int) {
        guard generation == focusGeneration, focusLock != nil else {
            return
        }
        if let error {
            focusLock?.failed()
            state.message = UserMessage(title: "Camera", text: PlatformText.focusNotLocked(error))
            return
        }
        focusLock?.locked(at: lensPosition)
        state.lockedLensPosition = lensPosition
    }

    /// Starts the frames; when the settings ask, locks exposure and white balance once
    /// auto-exposure has had time to settle, unless the camera stopped or changed meanwhile.
    private func startSession() {
        cameraGeneration += 1
        clearFocusLock()
        camera.start()
        guard let delay = CapturePlan(settings.settings).lockExposureAfter else {
            return
        }
        let generation = cameraGeneration
        schedule(delay) { [weak self] in
            guard let self, self.cameraGeneration == generation else {
                return
            }
            self.camera.lockExposureAndWhiteBalance { [weak self] problem in
                self?.deliver { self?.state.message = UserMessage(title: "Camera", text: problem) }
            }
        }
    }

    /// A new tracker for the `marker.json` in Documents (just saved by the marker calibration):
    /// tracking uses it from the next frame. The bite registration belongs to the old marker
    /// and goes with it.
    private func reloadMarker() throws {
        let newTracker = try Tracker(settings: trackerSettings(settings.settings), markerJson: try markerJSON())
        tracker = newTracker
        pipeline.use(tracker: newTracker)
    }

    /// The tracker's settings with the readout of the camera as configured (a calibrated value
    /// in the settings, else the device table's, else none; the library decides), and the
    /// choice shown. Before the camera is configured there is no model yet: readout 0.
    private func trackerSettings(_ app: AppSettings) -> Settings {
        var tracker = app.tracker
        tracker.readoutS = 0
        guard let configuration else {
            return tracker
        }
        do {
            let choice = try readoutFor(
                model: configuration.model, camera: configuration.camera, calibratedReadoutS: app.calibratedReadoutS
            )
            tracker.readoutS = choice.readoutS
            state.readout = choice
        } catch {
            state.readout = nil
            state.message = UserMessage(title: "Settings", text: userText(error))
        }
        return tracker
    }

    /// Hands the tracker `app`'s settings with the camera's readout.
    private func updateTrackerSettings(_ app: AppSettings) {
        pipeline.update(trackerSettings: trackerSettings(app)) { [weak self] error in
            guard let error else {
                return
            }
            let text = userText(error)
            self?.deliver { self?.state.message = UserMessage(title: "Tracker", text: text) }
        }
    }

    /// A calibrated marker file in Documents as `marker.json`: saved by the marker calibration,
    /// or made by `jawtrack calibrate-marker` and copied with the Files app; nil: the nominal
    /// marker.
    private func markerJSON() throws -> String? {
        guard let url = documents?.appendingPathComponent("marker.json"),
              FileManager.default.fileExists(atPath: url.path)
        else {
            return nil
        }
        do {
            return try String(contentsOf: url, encoding: .utf8)
        } catch {
            throw AppError(message: "marker.json in Documents could not be read: \(error.localizedDescription)")
        }
    }

    // MARK: Frames

    /// One frame's report on the screen; in focus mode planned, also its guidance, and the
    /// focus locked once the phone has been held still long enough (`FocusLock`). Internal for
    /// the tests, which hand it frames at depths the fixtures do not have.
    func show(_ report: FrameReport) {
        var next = state
        if let result = report.result {
            next.overlay = result.overlay
            next.status = TrackingStatus(result: result)
        } else {
            next.overlay = nil
            next.status.defocused = false
        }
        var lockNow = false
        if var lock = focusLock {
            let step = lock.frame(
                depthMm: report.result?.depthMm, defocused: report.result?.defocused ?? false,
                lensPosition: report.lensPosition, adjustingFocus: report.adjustingFocus
            )
            focusLock = lock
            next.guidance = step.guidance
            next.status.focusMoved = step.movedLensPosition.map {
                TrackingStatus.LensMove(lensPosition: $0, lockedAt: lock.lockedLensPosition ?? $0)
            }
            lockNow = step.lockNow
        }
        next.status.intrinsicsEstimated = report.intrinsicsEstimated
        next.status.exposure = report.exposure
        next.status.droppedFrames = report.droppedFrames
        next.status.problem = report.problem
        if let frames = report.recordedFrames {
            next.recordedFrames = frames
        }
        if let problem = report.recordingProblem {
            next.isRecording = false
            next.message = UserMessage(title: "Recording stopped", text: problem)
        }
        state = next
        if let progress = report.calibration {
            markerCalibration.show(progress)
        }
        if let cap = report.exposureCap {
            camera.limitExposure(to: cap)
        }
        if lockNow {
            lockFocus()
        }
    }

    // MARK: Settings

    /// Saves settings from the settings screen; the error text, or nil when saved.
    public func save(_ new: AppSettings) -> String? {
        do {
            try settings.save(new)
        } catch {
            return userText(error)
        }
        clearFocusLock()
        updateTrackerSettings(new)
        if state.isTransmitting {
            setTransmitting(false)
            setTransmitting(true)
        }
        return nil
    }

    // MARK: Recording

    public func toggleRecording() {
        state.isRecording ? stopRecording() : startRecording()
    }

    /// Starts recording; in focus mode planned, only once focus is locked (a recording is
    /// measured with one focal length).
    private func startRecording() {
        guard let documents else {
            state.message = UserMessage(title: "Recording", text: "The app's Documents folder is not available.")
            return
        }
        let current = settings.settings
        if let focusLock, !focusLock.isLocked {
            state.message = UserMessage(title: "Recording", text: focusLock.holdText)
            return
        }
        if focusLock == nil, current.focus == .planned {
            state.message = UserMessage(
                title: "Recording", text: "The camera is not set up for its capture plan yet, so focus cannot lock."
            )
            return
        }
        pipeline.startRecording(RecordingRequest(
            directory: documents,
            baseName: RecordingFiles.defaultName(at: Date(timeIntervalSince1970: clock())),
            settingsJSON: StoredSettings(current).headerJSON(),
            keyId: state.isTransmitting ? linkKeyId : nil,
            withVideo: current.recordVideo,
            planner: focusLock?.planner,
            lockedLensPosition: focusLock?.lockedLensPosition
        ))
        state.recordedFrames = 0
        state.isRecording = true
    }

    private func stopRecording() {
        state.isRecording = false
        pipeline.stopRecording { [weak self] result in
            self?.deliver { self?.recordingStopped(result) }
        }
    }

    private func recordingStopped(_ result: Result<RecordingFiles?, Error>) {
        switch result {
        case .success(let files?):
            state.finishedRecording = files
            state.recordingName = files.name
        case .success(.none):
            state.message = UserMessage(title: "Recording", text: "No frame was recorded.")
        case .failure(let error):
            state.message = UserMessage(title: "Recording", text: userText(error))
        }
    }

    /// What the naming alert says about where the files are.
    public static func savedText(_ files: RecordingFiles) -> String {
        files.video == nil
            ? "Saved in Files › On My iPhone › JawTrack."
            : "Saved with its video in Files › On My iPhone › JawTrack."
    }

    /// Gives the stopped recording its name (nil or blank: keeps the date and time).
    public func nameRecording(as name: String?) {
        guard let files = state.finishedRecording else {
            return
        }
        state.finishedRecording = nil
        do {
            let saved = try files.renamed(to: name ?? "")
            if let problem = saved.videoProblem {
                state.message = UserMessage(title: "Video", text: problem)
            }
        } catch {
            state.message = UserMessage(
                title: "Recording", text: "Saved as \(files.name), not renamed: \(error.localizedDescription)"
            )
        }
    }

    // MARK: Link

    public func setTransmitting(_ on: Bool) {
        pipeline.use(link: nil)
        link = nil
        state.isTransmitting = false
        state.light = AckLight()
        state.linkProblem = nil
        linkKeyId = nil
        guard on else {
            return
        }
        let current = settings.settings
        do {
            try validateAppSettings(settings: current, streaming: true)
            let encoder = try LinkEncoder(keyHex: current.pairingKey, insecurePlaintext: false)
            let deliver = self.deliver
            let newLink = try LinkSession(
                host: current.receiverHost,
                port: current.receiverPort,
                encoder: encoder,
                clock: clock,
                makeTransport: makeTransport,
                onAck: { [weak self] ack, time in deliver { self?.acknowledged(ack, at: time) } },
                onProblem: { [weak self] problem in deliver { self?.state.linkProblem = problem } }
            )
            newLink.start()
            pipeline.use(link: newLink)
            link = newLink
            linkKeyId = encoder.keyId()
            state.isTransmitting = true
        } catch {
            state.message = UserMessage(title: "Transmit", text: userText(error))
        }
    }

    private func acknowledged(_ ack: LinkAck, at time: Double) {
        guard state.isTransmitting else {
            return
        }
        state.light.acknowledged(ack, at: time)
    }

    // MARK: Calibration

    /// The maximal-intercuspation step: the patient bites; the library averages the last frames.
    public func calibrateBite() {
        state.isCalibrating = true
        pipeline.calibrate { [weak self] result in
            self?.deliver { self?.calibrated(result) }
        }
    }

    private func calibrated(_ result: Result<IntercuspationResult, Error>) {
        state.isCalibrating = false
        switch result {
        case .success(let bite):
            state.message = UserMessage(title: "Bite calibrated", text: Self.biteText(bite))
        case .failure(let error):
            state.message = UserMessage(title: "Calibration failed", text: userText(error))
        }
    }

    /// What the bite calibration tells the clinician.
    public static func biteText(_ bite: IntercuspationResult) -> String {
        String(
            format: "%u frames averaged over %.2f s; held within %.2f mm and %.2f°. The lower scan moved %.2f mm and turned %.2f°.",
            bite.frames, bite.spanS, bite.spreadMm, bite.spreadDeg, bite.translationMm, bite.rotationDeg
        )
    }

    /// Opens the marker calibration screen, unless recording.
    public func openMarkerCalibration() {
        guard state.canCalibrateMarker else {
            state.message = UserMessage(
                title: CalibrationText.title, text: "Stop the recording first: a recording keeps one marker file."
            )
            return
        }
        markerCalibration.open()
    }

    /// Dismisses the alert.
    public func dismissMessage() {
        state.message = nil
    }
}
