import Foundation
import JawTrackCore

/// What the pipeline made of one frame, for the screen.
public struct FrameReport {
    /// The tracker's result, when the frame was tracked.
    public var result: FrameResult?
    /// Why the frame was not tracked, or the link refused it.
    public var problem: String?
    /// The frame came without the camera's intrinsic matrix; the field-of-view estimate was used.
    public var intrinsicsEstimated = false
    /// The frame's exposure (s), when the camera said.
    public var exposure: Double?
    /// The frame's lens position (0 near – 1 far) and whether the camera was adjusting its
    /// focus, when the camera said.
    public var lensPosition: Double?
    public var adjustingFocus: Bool?
    /// Frames the camera dropped so far (gaps in the frame times).
    public var droppedFrames: UInt64 = 0
    /// Frames in the recording so far, while recording.
    public var recordedFrames: UInt64?
    /// Why the recording stopped by itself.
    public var recordingProblem: String?
    /// Where the marker calibration stands after this frame, while one collects views.
    public var calibration: CalibrationProgress?
    /// A new exposure cap for the camera (s), when this frame's gain called for one.
    public var exposureCap: Double?
}

/// Seconds the exposure cap is left alone after a change, for automatic exposure to settle at
/// it before the gain is read again.
let exposureCapSettle = 0.5

/// The per-frame work, on one serial queue that owns the tracker, the recorder and the link:
/// each frame is tracked in place (`FrameDoor`, no copy) with its own intrinsics and lens
/// position (the frame's, else where focus was locked), then its result goes to the marker
/// calibration (when one collects views), the recorder, the link and the screen. A frame older
/// than the last one is dropped, and gaps in the frame times are counted as frames the camera dropped (the capture
/// output discards frames that arrive while one is being tracked, so the queue never falls
/// behind).
public final class FramePipeline {
    public let queue: DispatchQueue

    private enum Recording {
        case idle
        case pending(RecordingRequest)
        case active(RecordingSession)
    }

    // Touched on `queue` only.
    private var onReport: ((FrameReport) -> Void)?
    private var tracker: Tracker?
    private var camera: CaptureConfiguration?
    private var makeVideo: VideoSinkFactory?
    private var link: LinkSession?
    /// The marker calibration each tracked frame is offered to, while it collects views.
    private var calibrator: Calibrator?
    private var recording = Recording.idle
    /// Why the recording ended outside a frame's turn, for the next frame's report.
    private var lateRecordingProblem: String?
    private var lastTime: Double?
    private var dropped: UInt64 = 0
    /// The exposure cap in force (s; nil: none) and when it last changed.
    private var exposureCap: Double?
    private var exposureCapChanged: Double?
    /// Where focus is locked (nil: not locked): the lens position of frames that do not say theirs.
    private var lockedLensPosition: Double?

    public init(queue: DispatchQueue = DispatchQueue(label: "org.jawtrack.frames", qos: .userInitiated)) {
        self.queue = queue
    }

    /// Where each frame's report goes (called on the pipeline's queue).
    public func setReportHandler(_ handler: @escaping (FrameReport) -> Void) {
        queue.async { self.onReport = handler }
    }

    /// Takes frames from `source`, on the pipeline's queue.
    public func attach(_ source: FrameSource) {
        source.deliverFrames(to: { [weak self] frame in self?.process(frame) }, on: queue)
    }

    public func use(tracker: Tracker?) {
        queue.async {
            self.tracker = tracker
            self.lastTime = nil
        }
    }

    /// The camera as configured, and how to make a movie writer for its format (nil: none).
    public func use(camera: CaptureConfiguration?, makeVideo: VideoSinkFactory?) {
        queue.async {
            self.camera = camera
            self.makeVideo = makeVideo
            self.lastTime = nil
            self.exposureCap = camera?.maxExposure
            self.exposureCapChanged = nil
        }
    }

    /// Focus locked at `lensPosition` (nil: no longer locked): the tracker is told at once, and
    /// frames that do not say their own lens position are stamped with it. `completion` gets
    /// the library's refusal of the value, or nil.
    public func focusLocked(at lensPosition: Double?, completion: @escaping (Error?) -> Void = { _ in }) {
        queue.async {
            do {
                try self.tracker?.setLensPosition(lensPosition: lensPosition)
                self.lockedLensPosition = lensPosition
                completion(nil)
            } catch {
                self.lockedLensPosition = nil
                completion(error)
            }
        }
    }

    /// Streams results through `link` (nil: stop streaming).
    public func use(link: LinkSession?) {
        queue.async {
            self.link?.stop()
            self.link = link
        }
    }

    /// Starts a marker calibration from the marker the tracker uses (a calibrated one starts
    /// afresh from the nominal marker of its size): every frame tracked from now on is offered
    /// to it as a view, and its report says where the calibration stands.
    public func startMarkerCalibration(minViews: UInt32, completion: @escaping (Result<Calibrator, Error>) -> Void) {
        queue.async {
            guard let tracker = self.tracker else {
                completion(.failure(AppError(message: "The tracker is not running.")))
                return
            }
            do {
                let calibrator = try Calibrator(markerJson: tracker.markerJson(), minViews: minViews)
                self.calibrator = calibrator
                completion(.success(calibrator))
            } catch {
                completion(.failure(error))
            }
        }
    }

    /// Offers the frames tracked from now on to `calibrator` (nil: to none).
    public func feed(calibrator: Calibrator?) {
        queue.async { self.calibrator = calibrator }
    }

    public func update(trackerSettings: JawTrackCore.Settings, completion: @escaping (Error?) -> Void) {
        queue.async {
            do {
                try self.tracker?.updateSettings(settings: trackerSettings)
                completion(nil)
            } catch {
                completion(error)
            }
        }
    }

    /// The maximal-intercuspation step over the frames tracked last (the library judges whether
    /// they are a held bite). An accepted bite's rest position goes into the running recording,
    /// so that its readers measure from it; if it cannot be written, the recording ends and
    /// the next frame's report says why.
    public func calibrate(completion: @escaping (Result<IntercuspationResult, Error>) -> Void) {
        queue.async {
            guard let tracker = self.tracker else {
                completion(.failure(AppError(message: "The tracker is not running.")))
                return
            }
            let result = Result { try tracker.calibrateIntercuspation() }
            if case .success(let bite) = result, case .active(let session) = self.recording {
                do {
                    try session.appendBite(bite)
                } catch {
                    self.recording = .idle
                    session.finish { _ in }
                    self.lateRecordingProblem = "\(userText(error)) What was recorded is in Files."
                }
            }
            completion(result)
        }
    }

    public func startRecording(_ request: RecordingRequest) {
        queue.async { self.recording = .pending(request) }
    }

    /// Ends the recording; its files, or nil when no frame was recorded.
    public func stopRecording(completion: @escaping (Result<RecordingFiles?, Error>) -> Void) {
        queue.async {
            let state = self.recording
            self.recording = .idle
            switch state {
            case .idle, .pending:
                completion(.success(nil))
            case .active(let session):
                session.finish { result in completion(result.map { Optional($0) }) }
            }
        }
    }

    /// Tracks one frame; call on `queue`, while the frame's pixels are held.
    public func process(_ frame: CameraFrame) {
        dispatchPrecondition(condition: .onQueue(queue))
        guard let tracker, let camera else {
            return
        }
        if let lastTime {
            guard frame.time > lastTime else {
                dropped += 1
                return
            }
            let frames = (frame.time - lastTime) / camera.frameDuration
            if frames > 1.5 {
                dropped += UInt64((frames - 1).rounded())
            }
        }
        lastTime = frame.time
        var report = FrameReport()
        report.exposure = frame.exposure
        report.lensPosition = frame.lensPosition
        report.adjustingFocus = frame.adjustingFocus
        report.droppedFrames = dropped
        report.exposureCap = adjustExposureCap(frame, camera: camera)
        var intrinsics: Intrinsics?
        do {
            let resolved = try CameraPlanner.intrinsics(
                cameraMatrix: frame.cameraMatrix, configuration: camera,
                width: frame.buffer.width, height: frame.buffer.height
            )
            report.intrinsicsEstimated = resolved.estimated
            intrinsics = resolved.intrinsics
            // Stamped on the result and recorded with the frame.
            try tracker.setLensPosition(lensPosition: frame.lensPosition ?? lockedLensPosition)
            try FrameDoor.track(
                frame.buffer, handle: tracker.frameHandle(), intrinsics: resolved.intrinsics, time: frame.time,
                exposure: frame.exposure
            )
            report.result = tracker.lastResult()
            report.calibration = calibrator?.addView(tracker: tracker)
        } catch {
            report.problem = userText(error)
        }
        record(frame, intrinsics: intrinsics, tracker: tracker, camera: camera, report: &report)
        if let link, let result = report.result {
            do {
                try link.send(frame: result.frame, of: tracker)
            } catch {
                report.problem = userText(error)
            }
        }
        onReport?(report)
    }

    /// The new exposure cap when the frame's gain calls for one (the library's rule, at most one
    /// change per `exposureCapSettle`), or nil.
    private func adjustExposureCap(_ frame: CameraFrame, camera: CaptureConfiguration) -> Double? {
        guard let requested = camera.maxExposure, let current = exposureCap, let iso = frame.iso else {
            return nil
        }
        if let changed = exposureCapChanged, frame.time - changed < exposureCapSettle {
            return nil
        }
        let next = nextExposureCap(requestedS: requested, currentS: current, iso: iso, maxIso: camera.maxISO)
        guard next != current, next > 0 else {
            return nil
        }
        exposureCap = next
        exposureCapChanged = frame.time
        return next
    }

    /// Opens a pending recording, then appends the frame (video) and its result (poses).
    private func record(
        _ frame: CameraFrame,
        intrinsics: Intrinsics?,
        tracker: Tracker,
        camera: CaptureConfiguration,
        report: inout FrameReport
    ) {
        if let problem = lateRecordingProblem {
            report.recordingProblem = problem
            lateRecordingProblem = nil
        }
        if case .pending(let request) = recording {
            guard let intrinsics else {
                return
            }
            let info = RecordingInfo(
                device: camera.deviceDescription,
                intrinsics: intrinsics,
                markerJson: tracker.markerJson(),
                settingsJson: request.settingsJSON,
                keyId: request.keyId,
                readoutS: tracker.settings().readoutS,
                plan: request.planner,
                lockedLensPosition: request.lockedLensPosition
            )
            do {
                recording = .active(try RecordingSession(request: request, info: info, makeVideo: makeVideo))
            } catch {
                recording = .idle
                report.recordingProblem = userText(error)
                return
            }
        }
        guard case .active(let session) = recording else {
            return
        }
        session.appendVideo(frame)
        guard let result = report.result else {
            return
        }
        do {
            try session.append(frame: result.frame, of: tracker)
            report.recordedFrames = session.framesWritten
        } catch {
            recording = .idle
            session.finish { _ in }
            report.recordingProblem = "\(userText(error)) What was recorded is in Files."
        }
    }
}
