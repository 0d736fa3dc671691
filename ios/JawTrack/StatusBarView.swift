import JawTrackCore
import SwiftUI

/// What the status bar shows of the last frame.
struct TrackingStatus: Equatable {
    /// One jaw: the tags used for its pose (or, when unsolved, detected on it) and whether it
    /// was solved.
    struct Jaw: Equatable {
        var tags = 0
        var solved = false
    }

    var maxilla = Jaw()
    var mandible = Jaw()
    /// Detection plus pose time (ms).
    var processingMs = 0.0
    var fps = 0.0
    var flags: [String] = []
    var intrinsicsEstimated = false
    var problem: String?

    init() {}

    init(result: FrameResult, intrinsicsEstimated: Bool) {
        maxilla = Self.jaw(result.maxilla, detected: result.overlay.tags.filter { $0.body == "maxilla" }.count)
        mandible = Self.jaw(result.mandible, detected: result.overlay.tags.filter { $0.body == "mandible" }.count)
        processingMs = result.detectionMs + result.poseMs
        fps = result.fps
        flags = result.flags
        self.intrinsicsEstimated = intrinsicsEstimated
    }

    private static func jaw(_ pose: BodyPose?, detected: Int) -> Jaw {
        guard let pose else {
            return Jaw(tags: detected, solved: false)
        }
        return Jaw(tags: pose.tags.count, solved: true)
    }
}

/// The line over the preview: tags per jaw, processing time, frame rate, the link light (green
/// only while the receiver's acknowledgements arrive, one within the last second), recording.
@MainActor
struct StatusBarView: View {
    let status: TrackingStatus
    let isTransmitting: Bool
    let lastAckAt: Date?
    let lastAck: LinkAck?
    let linkProblem: String?
    let isRecording: Bool
    let recordedFrames: UInt64

    var body: some View {
        VStack(alignment: .leading, spacing: 3) {
            HStack(spacing: 10) {
                jawLabel("Maxilla", status.maxilla)
                jawLabel("Mandible", status.mandible)
                Text(verbatim: String(format: "%.1f ms", status.processingMs))
                Text(verbatim: String(format: "%.0f fps", status.fps))
                if isTransmitting {
                    linkLight
                }
                if isRecording {
                    Text(verbatim: "● REC \(recordedFrames)")
                        .foregroundColor(.red)
                }
            }
            if let problem = status.problem {
                Text(verbatim: problem)
                    .foregroundColor(.orange)
                    .lineLimit(2)
            } else if !status.flags.isEmpty {
                Text(verbatim: status.flags.joined(separator: ", "))
                    .foregroundColor(.yellow)
                    .lineLimit(1)
            }
            if status.intrinsicsEstimated {
                Text("Intrinsics estimated from the field of view")
                    .foregroundColor(.yellow)
            }
            if isTransmitting, let linkProblem {
                Text(verbatim: linkProblem)
                    .foregroundColor(.orange)
                    .lineLimit(2)
            }
        }
        .font(.caption.monospacedDigit())
        .foregroundColor(.white)
        .padding(8)
        .background(Color.black.opacity(0.55))
        .clipShape(RoundedRectangle(cornerRadius: 8))
    }

    private func jawLabel(_ name: String, _ jaw: TrackingStatus.Jaw) -> some View {
        Text(verbatim: "\(name) \(jaw.tags)")
            .foregroundColor(jaw.solved ? .green : .orange)
    }

    /// Re-evaluated four times a second, so the light turns red when acknowledgements stop even
    /// if no new frame arrives.
    private var linkLight: some View {
        TimelineView(.periodic(from: .now, by: 0.25)) { context in
            let alive = lastAckAt.map { context.date.timeIntervalSince($0) < 1 } ?? false
            HStack(spacing: 4) {
                Circle()
                    .fill(alive ? Color.green : Color.red)
                    .frame(width: 8, height: 8)
                Text(verbatim: linkText(alive: alive))
                    .foregroundColor(alive ? .green : .red)
            }
        }
    }

    private func linkText(alive: Bool) -> String {
        guard let lastAck else {
            return "LINK: no ack"
        }
        return alive ? "LINK lost \(lastAck.lost)" : "LINK: no ack (lost \(lastAck.lost))"
    }
}
