import AVFoundation
import Foundation
import JawTrackCore
import SwiftUI
import UIKit

/// The screen's state and the buttons' actions, on the main actor. It wires the pieces
/// together and holds no tracking logic: the camera (`CameraController`), the per-frame work on
/// its own queue (`FramePipeline`), the overlay (`OverlayRenderer`) and the settings
/// (`SettingsStore`). Results come back from the pipeline's queue as `FrameReport`s.
@MainActor
final class AppModel: ObservableObject {
    @Published private(set) var status = TrackingStatus()
    @Published private(set) var isRecording = false
    @Published private(set) var recordedFrames: UInt64 = 0
    @Published private(set) var isTransmitting = false
    @Published private(set) var lastAckAt: Date?
    @Published private(set) var lastAck: LinkAck?
    @Published private(set) var linkProblem: String?
    @Published private(set) var isCalibrating = false
    @Published private(set) var configurationID = 0
    /// The alert on screen, if any.
    @Published var message: UserMessage?
    /// A stopped recording waiting for its name.
    @Published private(set) var finishedRecording: RecordingFiles?
    @Published var isNamingRecording = false
    @Published var recordingName = ""

    let settingsStore: SettingsStore
    let overlay: OverlayRenderer
    let camera: CameraController
    private let pipeline: FramePipeline
    private var tracker: Tracker?
    private var linkKeyId: String?
    private var started = false
    private var cameraReady = false
    private var settingsOpen = false

    init() {
        settingsStore = SettingsStore()
        overlay = OverlayRenderer()
        camera = CameraController()
        pipeline = FramePipeline()
        pipeline.setReportHandler { [weak self] report in
            Task { @MainActor in self?.show(report) }
        }
    }

    // MARK: Camera

    /// First appearance: camera permission, the tracker, the camera.
    func start() {
        guard !started else {
            return
        }
        started = true
        UIApplication.shared.isIdleTimerDisabled = true
        if let problem = settingsStore.loadProblem {
            message = UserMessage(title: "Settings", text: problem)
        }
        Task {
            guard await Self.cameraAllowed() else {
                self.message = UserMessage(
                    title: "Camera",
                    text: "JawTrack needs the camera to track the markers. Allow it in Settings › Privacy & Security › Camera."
                )
                return
            }
            self.startCamera()
        }
    }

    func scenePhaseChanged(_ phase: ScenePhase) {
        switch phase {
        case .background:
            camera.stop()
        case .active:
            if cameraReady, !settingsOpen {
                startSession()
            }
        default:
            break
        }
    }

    /// The settings screen takes the camera (for the QR scanner).
    func settingsOpened() {
        settingsOpen = true
        camera.stop()
    }

    /// Back from the settings screen: the camera again, with the settings as saved.
    func settingsClosed() {
        settingsOpen = false
        startCamera()
    }

    private func startCamera() {
        if tracker == nil {
            do {
                let newTracker = try Tracker(settings: settingsStore.settings.tracker, markerJson: try Self.markerJSON())
                tracker = newTracker
                pipeline.use(tracker: newTracker)
            } catch {
                message = UserMessage(title: "Tracker", text: userText(error))
                return
            }
        }
        cameraReady = false
        camera.configure(settingsStore.settings, delegate: pipeline, delegateQueue: pipeline.queue) { [weak self] result in
            Task { @MainActor in self?.cameraConfigured(result) }
        }
    }

    private func cameraConfigured(_ result: Result<CaptureConfiguration, Error>) {
        switch result {
        case .success(let configuration):
            pipeline.use(camera: configuration)
            cameraReady = true
            configurationID += 1
            if !settingsOpen {
                startSession()
            }
        case .failure(let error):
            message = UserMessage(title: "Camera", text: userText(error))
        }
    }

    private func startSession() {
        camera.start(lockingExposure: settingsStore.settings.exposureLocked) { [weak self] problem in
            Task { @MainActor in self?.message = UserMessage(title: "Camera", text: problem) }
        }
    }

    private static func cameraAllowed() async -> Bool {
        switch AVCaptureDevice.authorizationStatus(for: .video) {
        case .authorized:
            return true
        case .notDetermined:
            return await withCheckedContinuation { continuation in
                AVCaptureDevice.requestAccess(for: .video) { granted in
                    continuation.resume(returning: granted)
                }
            }
        default:
            return false
        }
    }

    /// A calibrated marker file put in the app's Documents as `marker.json` (from `jawtrack
    /// calibrate-marker`, copied with the Files app); nil: the nominal marker.
    private static func markerJSON() throws -> String? {
        guard let url = documentsDirectory()?.appendingPathComponent("marker.json"),
              FileManager.default.fileExists(atPath: url.path)
        else {
            return nil
        }
        return try String(contentsOf: url, encoding: .utf8)
    }

    private static func documentsDirectory() -> URL? {
        FileManager.default.urls(for: .documentDirectory, in: .userDomainMask).first
    }

    // MARK: Frames

    private func show(_ report: FrameReport) {
        if let result = report.result {
            overlay.render(result.overlay)
            status = TrackingStatus(result: result, intrinsicsEstimated: report.intrinsicsEstimated)
        } else {
            overlay.render(nil)
            status.intrinsicsEstimated = report.intrinsicsEstimated
        }
        status.problem = report.problem
        if let frames = report.recordedFrames {
            recordedFrames = frames
        }
        if let problem = report.recordingProblem {
            isRecording = false
            message = UserMessage(title: "Recording stopped", text: problem)
        }
    }

    // MARK: Settings

    /// Saves settings from the settings screen; the error text, or nil when saved.
    func save(_ settings: AppSettings) -> String? {
        do {
            try validateAppSettings(settings: settings, streaming: false)
            try settingsStore.save(settings)
        } catch {
            return userText(error)
        }
        pipeline.update(trackerSettings: settings.tracker) { [weak self] error in
            guard let error else {
                return
            }
            let text = userText(error)
            Task { @MainActor in self?.message = UserMessage(title: "Tracker", text: text) }
        }
        if isTransmitting {
            setTransmitting(false)
            setTransmitting(true)
        }
        return nil
    }

    // MARK: Recording

    func toggleRecording() {
        if isRecording {
            stopRecording()
        } else {
            startRecording()
        }
    }

    private func startRecording() {
        guard let documents = Self.documentsDirectory() else {
            message = UserMessage(title: "Recording", text: "The app's Documents folder is not available.")
            return
        }
        let settings = settingsStore.settings
        pipeline.startRecording(RecordingRequest(
            directory: documents,
            baseName: RecordingFiles.defaultName(at: Date()),
            settingsJSON: StoredSettings(settings).headerJSON(),
            keyId: isTransmitting ? linkKeyId : nil,
            withVideo: settings.recordVideo
        ))
        recordedFrames = 0
        isRecording = true
    }

    private func stopRecording() {
        isRecording = false
        pipeline.stopRecording { [weak self] result in
            Task { @MainActor in self?.recordingStopped(result) }
        }
    }

    private func recordingStopped(_ result: Result<RecordingFiles?, Error>) {
        switch result {
        case .success(let files?):
            finishedRecording = files
            recordingName = files.name
            isNamingRecording = true
        case .success(.none):
            message = UserMessage(title: "Recording", text: "No frame was recorded.")
        case .failure(let error):
            message = UserMessage(title: "Recording", text: userText(error))
        }
    }

    /// Gives the stopped recording its name (nil or blank: keeps the date and time).
    func nameRecording(_ files: RecordingFiles, as name: String?) {
        finishedRecording = nil
        do {
            let saved = try files.renamed(to: name ?? "")
            if let problem = saved.videoProblem {
                message = UserMessage(title: "Video", text: problem)
            }
        } catch {
            message = UserMessage(title: "Recording", text: "Saved as \(files.name), not renamed: \(error.localizedDescription)")
        }
    }

    // MARK: Link

    func setTransmitting(_ on: Bool) {
        pipeline.use(link: nil)
        isTransmitting = false
        lastAckAt = nil
        lastAck = nil
        linkProblem = nil
        linkKeyId = nil
        guard on else {
            return
        }
        let settings = settingsStore.settings
        do {
            try validateAppSettings(settings: settings, streaming: true)
            let encoder = try LinkEncoder(keyHex: settings.pairingKey, insecurePlaintext: false)
            let link = try LinkStreamer(
                host: settings.receiverHost.trimmingCharacters(in: .whitespacesAndNewlines),
                port: settings.receiverPort,
                encoder: encoder,
                onAck: { [weak self] ack in
                    Task { @MainActor in self?.acknowledged(ack) }
                },
                onProblem: { [weak self] problem in
                    Task { @MainActor in self?.linkProblem = problem }
                }
            )
            link.start()
            pipeline.use(link: link)
            linkKeyId = encoder.keyId()
            isTransmitting = true
        } catch {
            message = UserMessage(title: "Transmit", text: userText(error))
        }
    }

    private func acknowledged(_ ack: LinkAck) {
        guard isTransmitting else {
            return
        }
        lastAck = ack
        lastAckAt = Date()
        linkProblem = nil
    }

    // MARK: Calibration

    /// The maximal-intercuspation step: the patient bites; the library averages the last frames.
    func calibrateBite() {
        isCalibrating = true
        pipeline.calibrate { [weak self] result in
            Task { @MainActor in self?.calibrated(result) }
        }
    }

    private func calibrated(_ result: Result<IntercuspationResult, Error>) {
        isCalibrating = false
        switch result {
        case .success(let bite):
            let text = String(
                format: "%u frames averaged; spread %.2f mm. The lower scan moved %.2f mm and turned %.2f°.",
                bite.frames, bite.spreadMm, bite.translationMm, bite.rotationDeg
            )
            message = UserMessage(title: "Bite calibrated", text: text)
        case .failure(let error):
            message = UserMessage(title: "Calibration failed", text: userText(error))
        }
    }
}
