import AVFoundation
import Foundation
import JawTrackCore

/// The files of one recording, in the app's Documents (the Files app shows them under
/// On My iPhone › JawTrack).
struct RecordingFiles {
    /// The poses: JSON Lines in the schema of `jawtrack track`.
    let poses: URL
    /// The camera's frames, when recorded.
    let video: URL?
    /// Why the video is missing or cut short, if it is.
    let videoProblem: String?

    /// The name both files share.
    var name: String { poses.deletingPathExtension().lastPathComponent }

    /// A name nobody has to type: the date and time.
    static func defaultName(at date: Date) -> String {
        let formatter = DateFormatter()
        formatter.locale = Locale(identifier: "en_US_POSIX")
        formatter.dateFormat = "yyyy-MM-dd HH.mm.ss"
        return "JawTrack \(formatter.string(from: date))"
    }

    /// Both files renamed to `name` (slashes and colons replaced; a number added when the name
    /// is taken). A blank name keeps the current one.
    func renamed(to name: String) throws -> RecordingFiles {
        let cleaned = name
            .trimmingCharacters(in: .whitespacesAndNewlines)
            .replacingOccurrences(of: "/", with: "-")
            .replacingOccurrences(of: ":", with: "-")
        guard !cleaned.isEmpty, cleaned != self.name else {
            return self
        }
        let directory = poses.deletingLastPathComponent()
        let files = FileManager.default
        func taken(_ candidate: String) -> Bool {
            files.fileExists(atPath: directory.appendingPathComponent(candidate + ".jsonl").path)
                || files.fileExists(atPath: directory.appendingPathComponent(candidate + ".mov").path)
        }
        var candidate = cleaned
        var number = 2
        while taken(candidate) {
            candidate = "\(cleaned) \(number)"
            number += 1
        }
        let newPoses = directory.appendingPathComponent(candidate + ".jsonl")
        try files.moveItem(at: poses, to: newPoses)
        var newVideo: URL?
        if let video {
            let target = directory.appendingPathComponent(candidate + ".mov")
            try files.moveItem(at: video, to: target)
            newVideo = target
        }
        return RecordingFiles(poses: newPoses, video: newVideo, videoProblem: videoProblem)
    }
}

/// One recording: the poses through the library's `Recorder` (its header carries the device,
/// intrinsics, marker and settings; each frame's line is flushed as written) and, when asked,
/// the frames as the sensor delivered them in a .mov (no rotation applied, so the recorded
/// intrinsics hold), for re-tracking with `jawtrack track --video`. No audio.
/// Used on the frame pipeline's queue only.
final class SessionRecorder {
    let files: RecordingFiles

    private let recorder: Recorder
    private let writer: AVAssetWriter?
    private let input: AVAssetWriterInput?

    /// Frames appended so far.
    var framesWritten: UInt64 { recorder.framesWritten() }

    init(request: RecordingRequest, info: RecordingInfo, videoSettings: [String: Any]?) throws {
        let base = request.directory.appendingPathComponent(request.baseName)
        let poses = base.appendingPathExtension("jsonl")
        var writer: AVAssetWriter?
        var input: AVAssetWriterInput?
        var video: URL?
        if request.withVideo {
            guard let videoSettings else {
                throw AppError(message: "This camera format offers no video encoder; turn video recording off.")
            }
            let url = base.appendingPathExtension("mov")
            let newWriter = try AVAssetWriter(outputURL: url, fileType: .mov)
            let newInput = AVAssetWriterInput(mediaType: .video, outputSettings: videoSettings)
            newInput.expectsMediaDataInRealTime = true
            guard newWriter.canAdd(newInput) else {
                throw AppError(message: "The video cannot be written with this camera format.")
            }
            newWriter.add(newInput)
            writer = newWriter
            input = newInput
            video = url
        }
        recorder = try Recorder.open(path: poses.path, info: info)
        self.writer = writer
        self.input = input
        files = RecordingFiles(poses: poses, video: video, videoProblem: nil)
    }

    /// Appends a frame's result to the poses file.
    func append(_ result: FrameResult) throws {
        try recorder.append(result: result)
    }

    /// Appends the camera frame to the video, if one is recorded; a frame the encoder is not
    /// ready for is dropped, as the capture output would.
    func appendVideo(_ sampleBuffer: CMSampleBuffer) {
        guard let writer, let input else {
            return
        }
        if writer.status == .unknown {
            guard writer.startWriting() else {
                return
            }
            writer.startSession(atSourceTime: CMSampleBufferGetPresentationTimeStamp(sampleBuffer))
        }
        guard writer.status == .writing, input.isReadyForMoreMediaData else {
            return
        }
        _ = input.append(sampleBuffer)
    }

    /// Closes the poses file and finishes the video; `completion` gets the files (from the
    /// writer's queue when there is a video).
    func finish(completion: @escaping @Sendable (Result<RecordingFiles, Error>) -> Void) {
        let closed = Result { try recorder.close() }
        let files = self.files
        guard let writer, let input else {
            completion(closed.map { _ in files })
            return
        }
        switch writer.status {
        case .writing:
            input.markAsFinished()
            writer.finishWriting {
                let problem = writer.status == .completed ? nil : Self.problem(of: writer)
                completion(closed.map { _ in Self.files(files, videoProblem: problem) })
            }
        case .failed:
            completion(closed.map { _ in Self.files(files, videoProblem: Self.problem(of: writer)) })
        default:
            completion(closed.map { _ in RecordingFiles(poses: files.poses, video: nil, videoProblem: "No video frame was written.") })
        }
    }

    private static func problem(of writer: AVAssetWriter) -> String {
        "The video could not be finished: \(writer.error?.localizedDescription ?? "unknown error")"
    }

    private static func files(_ files: RecordingFiles, videoProblem: String?) -> RecordingFiles {
        RecordingFiles(poses: files.poses, video: files.video, videoProblem: videoProblem)
    }
}
