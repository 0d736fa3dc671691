import AVFoundation
import Foundation
import JawTrackCore
import simd

/// What the pipeline made of one frame, for the screen.
struct FrameReport {
    /// The tracker's result, when the frame was tracked.
    var result: FrameResult?
    /// Why the frame was not tracked, or the link refused it.
    var problem: String?
    /// The frame came without AVFoundation's intrinsic matrix; one from the field of view was used.
    var intrinsicsEstimated = false
    /// Frames in the recording so far, while recording.
    var recordedFrames: UInt64?
    /// Why the recording stopped by itself.
    var recordingProblem: String?
}

/// A recording asked for from the screen. The recorder opens on the next frame, once the
/// camera's intrinsics (which go into the header) are known.
struct RecordingRequest {
    let directory: URL
    let baseName: String
    let settingsJSON: String?
    let keyId: String?
    let withVideo: Bool
}

/// The per-frame work, on one serial queue that owns the tracker, the recorder and the link:
/// each camera frame is tracked in place (`FramePath`, no copy), then its result goes to the
/// recorder, the link and the screen. The capture output drops frames that arrive while one is
/// being tracked, so the queue never falls behind.
final class FramePipeline: NSObject, AVCaptureVideoDataOutputSampleBufferDelegate {
    let queue = DispatchQueue(label: "org.jawtrack.frames", qos: .userInitiated)

    private enum Recording {
        case idle
        case pending(RecordingRequest)
        case active(SessionRecorder)
    }

    // Touched on `queue` only.
    private var onReport: (@Sendable (FrameReport) -> Void)?
    private var tracker: Tracker?
    private var camera: CaptureConfiguration?
    private var link: LinkStreamer?
    private var recording = Recording.idle

    /// Where each frame's report goes (called on the pipeline's queue).
    func setReportHandler(_ handler: @escaping @Sendable (FrameReport) -> Void) {
        queue.async { self.onReport = handler }
    }

    func use(tracker: Tracker?) {
        queue.async { self.tracker = tracker }
    }

    func use(camera: CaptureConfiguration?) {
        queue.async { self.camera = camera }
    }

    /// Streams results through `link` (nil: stop streaming).
    func use(link: LinkStreamer?) {
        queue.async {
            self.link?.stop()
            self.link = link
        }
    }

    func update(trackerSettings: JawTrackCore.Settings, completion: @escaping @Sendable (Error?) -> Void) {
        queue.async {
            do {
                try self.tracker?.updateSettings(settings: trackerSettings)
                completion(nil)
            } catch {
                completion(error)
            }
        }
    }

    /// The maximal-intercuspation step over the frames tracked so far.
    func calibrate(completion: @escaping @Sendable (Result<IntercuspationResult, Error>) -> Void) {
        queue.async {
            guard let tracker = self.tracker else {
                completion(.failure(AppError(message: "The tracker is not running.")))
                return
            }
            completion(Result { try tracker.calibrateIntercuspation() })
        }
    }

    func startRecording(_ request: RecordingRequest) {
        queue.async { self.recording = .pending(request) }
    }

    /// Ends the recording; its files, or nil when no frame was recorded.
    func stopRecording(completion: @escaping @Sendable (Result<RecordingFiles?, Error>) -> Void) {
        queue.async {
            let state = self.recording
            self.recording = .idle
            switch state {
            case .idle, .pending:
                completion(.success(nil))
            case .active(let recorder):
                recorder.finish { result in completion(result.map { Optional($0) }) }
            }
        }
    }

    func captureOutput(_ output: AVCaptureOutput, didOutput sampleBuffer: CMSampleBuffer, from connection: AVCaptureConnection) {
        guard let tracker, let camera, let pixelBuffer = CMSampleBufferGetImageBuffer(sampleBuffer) else {
            return
        }
        var report = FrameReport()
        var intrinsics: Intrinsics?
        do {
            let delivered = Self.intrinsicMatrix(of: sampleBuffer)
            report.intrinsicsEstimated = delivered == nil
            let frameIntrinsics = try intrinsicsFromCameraMatrix(
                matrix: delivered ?? camera.estimatedMatrix,
                referenceWidth: camera.referenceWidth,
                referenceHeight: camera.referenceHeight,
                width: UInt32(clamping: CVPixelBufferGetWidth(pixelBuffer)),
                height: UInt32(clamping: CVPixelBufferGetHeight(pixelBuffer))
            )
            intrinsics = frameIntrinsics
            let time = CMSampleBufferGetPresentationTimeStamp(sampleBuffer).seconds
            try FramePath.track(pixelBuffer, handle: tracker.frameHandle(), intrinsics: frameIntrinsics, time: time)
            report.result = tracker.lastResult()
        } catch {
            report.problem = userText(error)
        }
        record(sampleBuffer, intrinsics: intrinsics, tracker: tracker, camera: camera, report: &report)
        if let link, let result = report.result {
            do {
                try link.send(result)
            } catch {
                report.problem = userText(error)
            }
        }
        onReport?(report)
    }

    /// Opens a pending recording, then appends the frame (video) and its result (poses).
    private func record(
        _ sampleBuffer: CMSampleBuffer,
        intrinsics: Intrinsics?,
        tracker: Tracker,
        camera: CaptureConfiguration,
        report: inout FrameReport
    ) {
        if case .pending(let request) = recording {
            guard let intrinsics else {
                return
            }
            let info = RecordingInfo(
                device: camera.deviceDescription,
                intrinsics: intrinsics,
                markerJson: tracker.markerJson(),
                settingsJson: request.settingsJSON,
                keyId: request.keyId
            )
            do {
                let recorder = try SessionRecorder(request: request, info: info, videoSettings: camera.videoSettings)
                recording = .active(recorder)
            } catch {
                recording = .idle
                report.recordingProblem = userText(error)
                return
            }
        }
        guard case .active(let recorder) = recording else {
            return
        }
        recorder.appendVideo(sampleBuffer)
        guard let result = report.result else {
            return
        }
        do {
            try recorder.append(result)
            report.recordedFrames = recorder.framesWritten
        } catch {
            recording = .idle
            recorder.finish { _ in }
            report.recordingProblem = "\(userText(error)) What was recorded is in Files."
        }
    }

    /// AVFoundation's intrinsic matrix for this frame: a `matrix_float3x3` in a CFData,
    /// column-major, as nine numbers.
    private static func intrinsicMatrix(of sampleBuffer: CMSampleBuffer) -> [Float]? {
        guard
            let attachment = CMGetAttachment(
                sampleBuffer,
                key: kCMSampleBufferAttachmentKey_CameraIntrinsicMatrix,
                attachmentModeOut: nil
            ),
            let data = attachment as? Data,
            data.count >= MemoryLayout<matrix_float3x3>.size
        else {
            return nil
        }
        var matrix = matrix_float3x3()
        _ = withUnsafeMutableBytes(of: &matrix) { data.copyBytes(to: $0) }
        let (c0, c1, c2) = matrix.columns
        return [c0.x, c0.y, c0.z, c1.x, c1.y, c1.z, c2.x, c2.y, c2.z]
    }
}
