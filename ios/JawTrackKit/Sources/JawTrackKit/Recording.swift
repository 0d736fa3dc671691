import Foundation
import JawTrackCore

/// The files of one recording, in the app's Documents (the Files app shows them under
/// On My iPhone › JawTrack).
public struct RecordingFiles: Equatable {
    /// The poses: JSON Lines in the schema of `jawtrack track`.
    public let poses: URL
    /// The camera's frames, when recorded.
    public let video: URL?
    /// Why the video is missing or cut short, if it is.
    public let videoProblem: String?

    public init(poses: URL, video: URL?, videoProblem: String?) {
        self.poses = poses
        self.video = video
        self.videoProblem = videoProblem
    }

    /// The name both files share.
    public var name: String { poses.deletingPathExtension().lastPathComponent }

    /// A name nobody has to type: the date and time, e.g. "JawTrack 2026-11-25 10.42.07".
    public static func defaultName(at date: Date, timeZone: TimeZone = .current) -> String {
        let formatter = DateFormatter()
        formatter.locale = Locale(identifier: "en_US_POSIX")
        formatter.timeZone = timeZone
        formatter.dateFormat = "yyyy-MM-dd HH.mm.ss"
        return "JawTrack \(formatter.string(from: date))"
    }

    /// A name as typed, made safe for a file name: trimmed, slashes and colons replaced, no
    /// leading dot (a hidden file); "" when nothing is left.
    public static func cleanedName(_ name: String) -> String {
        var cleaned = name
            .trimmingCharacters(in: .whitespacesAndNewlines)
            .replacingOccurrences(of: "/", with: "-")
            .replacingOccurrences(of: ":", with: "-")
        while cleaned.hasPrefix(".") {
            cleaned.removeFirst()
        }
        return cleaned
    }

    /// The first of `base`, "base 2", "base 3", … for which neither file exists in `directory`.
    public static func freeName(_ base: String, in directory: URL, fileManager: FileManager = .default) -> String {
        func taken(_ candidate: String) -> Bool {
            ["jsonl", "mov"].contains { fileManager.fileExists(atPath: directory.appendingPathComponent("\(candidate).\($0)").path) }
        }
        var candidate = base
        var number = 2
        while taken(candidate) {
            candidate = "\(base) \(number)"
            number += 1
        }
        return candidate
    }

    /// Both files renamed to `name` (cleaned; a number added when the name is taken). A blank
    /// name keeps the current one.
    public func renamed(to name: String, fileManager: FileManager = .default) throws -> RecordingFiles {
        let cleaned = Self.cleanedName(name)
        guard !cleaned.isEmpty, cleaned != self.name else {
            return self
        }
        let directory = poses.deletingLastPathComponent()
        let candidate = Self.freeName(cleaned, in: directory, fileManager: fileManager)
        let newPoses = directory.appendingPathComponent(candidate + ".jsonl")
        try fileManager.moveItem(at: poses, to: newPoses)
        var newVideo: URL?
        if let video {
            let target = directory.appendingPathComponent(candidate + ".mov")
            try fileManager.moveItem(at: video, to: target)
            newVideo = target
        }
        return RecordingFiles(poses: newPoses, video: newVideo, videoProblem: videoProblem)
    }
}

/// A recording asked for from the screen. It opens on the next frame, once the camera's
/// intrinsics (which go into the header) are known.
public struct RecordingRequest: Equatable {
    public let directory: URL
    public let baseName: String
    public let settingsJSON: String?
    public let keyId: String?
    public let withVideo: Bool
    /// The capture plan the camera was set by (focus mode planned) and the lens position focus
    /// was locked at: both go into the header (`capture`).
    public let planner: CapturePlanner?
    public let lockedLensPosition: Double?

    public init(
        directory: URL, baseName: String, settingsJSON: String?, keyId: String?, withVideo: Bool,
        planner: CapturePlanner? = nil, lockedLensPosition: Double? = nil
    ) {
        self.directory = directory
        self.baseName = baseName
        self.settingsJSON = settingsJSON
        self.keyId = keyId
        self.withVideo = withVideo
        self.planner = planner
        self.lockedLensPosition = lockedLensPosition
    }

    /// The same plan object (the library's planner is a reference), and the rest equal.
    public static func == (a: RecordingRequest, b: RecordingRequest) -> Bool {
        a.directory == b.directory && a.baseName == b.baseName && a.settingsJSON == b.settingsJSON && a.keyId == b.keyId
            && a.withVideo == b.withVideo && a.planner === b.planner && a.lockedLensPosition == b.lockedLensPosition
    }
}

/// Writes the camera's frames to a movie (AVAssetWriter in the app). Used on the pipeline's
/// queue only.
public protocol VideoSink: AnyObject {
    /// Appends the frame (its `native` sample); false when it was dropped (encoder not ready).
    func append(_ frame: CameraFrame) -> Bool
    /// Finishes the movie; `completion` gets nil when it is complete, else why not.
    func finish(completion: @escaping (String?) -> Void)
}

/// Makes the movie writer for a file (AVAssetWriter with the format's recommended settings).
public typealias VideoSinkFactory = (URL) throws -> VideoSink

/// One recording: the poses through the library's `Recorder` (header with device, intrinsics,
/// marker, settings, and the capture plan with where focus was locked; each line flushed as
/// written, so a killed app leaves a readable file) and, when asked, the frames as the sensor delivered them in a .mov beside it (no rotation,
/// so the recorded intrinsics hold), for `jawtrack track --video`. Never overwrites: a taken
/// name gets a number. Used on the pipeline's queue only.
public final class RecordingSession {
    public let files: RecordingFiles
    private let recorder: Recorder
    private let video: VideoSink?
    public private(set) var videoFramesWritten: UInt64 = 0
    public private(set) var videoFramesDropped: UInt64 = 0

    /// Frames appended to the poses so far.
    public var framesWritten: UInt64 { recorder.framesWritten() }

    public init(request: RecordingRequest, info: RecordingInfo, makeVideo: VideoSinkFactory?) throws {
        let name = RecordingFiles.freeName(request.baseName, in: request.directory)
        let base = request.directory.appendingPathComponent(name)
        let poses = base.appendingPathExtension("jsonl")
        var video: VideoSink?
        var videoURL: URL?
        if request.withVideo {
            guard let makeVideo else {
                throw AppError(message: "This camera format offers no video encoder; turn video recording off.")
            }
            let url = base.appendingPathExtension("mov")
            video = try makeVideo(url)
            videoURL = url
        }
        recorder = try Recorder.open(path: poses.path, info: info)
        self.video = video
        files = RecordingFiles(poses: poses, video: videoURL, videoProblem: nil)
    }

    /// Appends frame `frame`, the one `tracker` just tracked, to the poses file; the library
    /// takes the result from the tracker itself.
    public func append(frame: UInt64, of tracker: Tracker) throws {
        try recorder.append(tracker: tracker, frame: frame)
    }

    /// Writes the rest position the bite step accepted into the poses file.
    public func appendBite(_ bite: IntercuspationResult) throws {
        try recorder.appendBite(bite: bite)
    }

    /// Appends the camera frame to the video, if one is recorded.
    public func appendVideo(_ frame: CameraFrame) {
        guard let video else {
            return
        }
        if video.append(frame) {
            videoFramesWritten += 1
        } else {
            videoFramesDropped += 1
        }
    }

    /// Closes the poses file and finishes the video; `completion` gets the files (the video's
    /// problem, if any, in `videoProblem`), or the poses file's error.
    public func finish(completion: @escaping (Result<RecordingFiles, Error>) -> Void) {
        let closed = Result { try recorder.close() }
        let files = self.files
        guard let video else {
            completion(closed.map { _ in files })
            return
        }
        guard videoFramesWritten > 0 else {
            video.finish { _ in }
            completion(closed.map { _ in RecordingFiles(poses: files.poses, video: nil, videoProblem: "No video frame was written.") })
            return
        }
        video.finish { problem in
            let problem = problem.map { "The video could not be finished: \($0)" }
            completion(closed.map { _ in RecordingFiles(poses: files.poses, video: files.video, videoProblem: problem) })
        }
    }
}
