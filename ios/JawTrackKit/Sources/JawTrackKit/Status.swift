import Foundation
import JawTrackCore

/// What the status bar shows of the last frame.
public struct TrackingStatus: Equatable {
    /// One jaw: the tags its pose used (or, unsolved, those detected on it) and whether it was solved.
    public struct Jaw: Equatable {
        public var tags = 0
        public var solved = false
    }

    public var maxilla = Jaw()
    public var mandible = Jaw()
    /// Detection plus pose time (ms).
    public var processingMs = 0.0
    public var fps = 0.0
    public var flags: [String] = []
    public var intrinsicsEstimated = false
    /// The frame's exposure (s), when the camera said.
    public var exposure: Double?
    /// Frames the camera dropped since tracking started (late or lost).
    public var droppedFrames: UInt64 = 0
    public var problem: String?

    public init() {}

    public init(result: FrameResult) {
        maxilla = Self.jaw(result.maxilla, detected: result.overlay.tags.filter { $0.body == "maxilla" }.count)
        mandible = Self.jaw(result.mandible, detected: result.overlay.tags.filter { $0.body == "mandible" }.count)
        processingMs = result.detectionMs + result.poseMs
        fps = result.fps
        flags = result.flags
    }

    private static func jaw(_ pose: BodyPose?, detected: Int) -> Jaw {
        guard let pose else {
            return Jaw(tags: detected, solved: false)
        }
        return Jaw(tags: pose.tags.count, solved: true)
    }
}

/// A colour the status bar uses, by meaning.
public enum StatusTone: Equatable {
    case normal, good, warning, problem, recording
}

/// One piece of text in the status bar.
public struct StatusItem: Equatable {
    public let text: String
    public let tone: StatusTone

    public init(text: String, tone: StatusTone) {
        self.text = text
        self.tone = tone
    }
}

/// The status bar's content, decided here and only laid out by the view: the first line
/// (jaws, timing, frame rate, link, recording), then at most one line each for the frame's
/// problem or flags (and one per jaw whose pose uses tags the marker's calibration left
/// nominal), estimated intrinsics, and the link's problem.
public struct StatusBar: Equatable {
    public let items: [StatusItem]
    /// Whether the link light is shown, and green.
    public let link: (shown: Bool, green: Bool, text: String)
    public let notes: [StatusItem]

    public init(
        status: TrackingStatus,
        transmitting: Bool,
        light: AckLight,
        linkProblem: String?,
        recording: Bool,
        recordedFrames: UInt64,
        now: Double
    ) {
        var items = [
            StatusItem(text: "Maxilla \(status.maxilla.tags)", tone: status.maxilla.solved ? .good : .warning),
            StatusItem(text: "Mandible \(status.mandible.tags)", tone: status.mandible.solved ? .good : .warning),
            StatusItem(text: String(format: "%.1f ms", status.processingMs), tone: .normal),
            StatusItem(text: String(format: "%.0f fps", status.fps), tone: .normal),
        ]
        if let exposure = status.exposure, exposure > 0 {
            items.append(StatusItem(text: Self.exposureText(exposure), tone: exposure > 0.004 ? .warning : .normal))
        }
        if recording {
            items.append(StatusItem(text: "● REC \(recordedFrames)", tone: .recording))
        }
        self.items = items
        link = (transmitting, light.isGreen(at: now), light.text(at: now))
        var notes: [StatusItem] = []
        if let problem = status.problem {
            notes.append(StatusItem(text: problem, tone: .problem))
        } else if !status.flags.isEmpty {
            notes.append(StatusItem(text: status.flags.joined(separator: ", "), tone: .warning))
            notes += Self.uncalibratedNotes(status.flags)
        }
        if status.droppedFrames > 0 {
            notes.append(StatusItem(text: "\(status.droppedFrames) frames dropped (tracking slower than the camera)", tone: .warning))
        }
        if status.intrinsicsEstimated {
            notes.append(StatusItem(text: "Intrinsics estimated from the field of view", tone: .warning))
        }
        if transmitting, let linkProblem {
            notes.append(StatusItem(text: linkProblem, tone: .problem))
        }
        self.notes = notes
    }

    /// The `BODY:uncalibrated_tag` flags in words: the jaw's pose uses tags that the calibrated
    /// marker file left at their nominal place.
    public static func uncalibratedNotes(_ flags: [String]) -> [StatusItem] {
        var notes: [StatusItem] = []
        for (body, words) in [("maxilla", "upper"), ("mandible", "lower")] {
            if flags.contains("\(body):uncalibrated_tag") {
                notes.append(StatusItem(text: "The \(words) marker rests on tags its calibration left nominal.", tone: .warning))
            }
        }
        return notes
    }

    /// An exposure as photographers write it: "1/500 s" (or "12 ms" when long).
    public static func exposureText(_ seconds: Double) -> String {
        if seconds >= 0.02 {
            return String(format: "%.0f ms", seconds * 1000)
        }
        return "1/\(Int((1 / seconds).rounded())) s"
    }

    public static func == (a: StatusBar, b: StatusBar) -> Bool {
        a.items == b.items && a.notes == b.notes && a.link.shown == b.link.shown && a.link.green == b.link.green
            && a.link.text == b.link.text
    }
}
