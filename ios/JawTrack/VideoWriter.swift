// Adapts AVAssetWriter to JawTrackKit's VideoSink: each frame's CMSampleBuffer, as the sensor
// delivered it, into a .mov from the first frame's time; finishing reports the writer's error.
import AVFoundation
import JawTrackKit

final class VideoWriter: VideoSink {
    private let writer: AVAssetWriter
    private let input: AVAssetWriterInput

    /// `settings`: the capture output's recommended settings for the codec.
    init(url: URL, settings: [String: Any]) throws {
        writer = try AVAssetWriter(outputURL: url, fileType: .mov)
        input = AVAssetWriterInput(mediaType: .video, outputSettings: settings)
        input.expectsMediaDataInRealTime = true
        guard writer.canAdd(input) else { throw PlatformText.videoInputRefused }
        writer.add(input)
    }

    func append(_ frame: CameraFrame) -> Bool {
        guard let native = frame.native else { return false }
        let sample = native as! CMSampleBuffer
        if writer.status == .unknown {
            guard writer.startWriting() else { return false }
            writer.startSession(atSourceTime: CMSampleBufferGetPresentationTimeStamp(sample))
        }
        return writer.status == .writing && input.isReadyForMoreMediaData && input.append(sample)
    }

    func finish(completion: @escaping (String?) -> Void) {
        guard writer.status == .writing else { return completion(problem) }
        input.markAsFinished()
        writer.finishWriting { [self] in completion(problem) }
    }

    /// Nil once the movie is complete, else the writer's error.
    private var problem: String? {
        writer.status == .completed ? nil : userText(writer.error ?? PlatformText.videoUnfinished)
    }
}
