import Foundation
import JawTrackCore

/// What the status bar shows of the last frame.
public struct TrackingStatus: Equatable {
    /// One jaw: the tags its pose used (or, unsolved, those detected on it) and whether it was solved.
    public struct Jaw: Equatable {
        public var tags = 0
        public var solved = false
    }

    /// The lens away from where focus was locked.
    public struct LensMove: Equatable {
        public let lensPosition: Double
        public let lockedAt: Double

        public init(lensPosition: Double, lockedAt: Double) {
            self.lensPosition = lensPosition
            self.lockedAt = lockedAt
        }
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
    /// A body's tags were blurred beyond what its pose can stand (`FrameResult.defocused`): the
    /// frame gives no jaw pose, and nothing of it is shown as good.
    public var defocused = false
    /// Focus is locked and this frame's lens is away from where it was locked: the focal length
    /// changed with it.
    public var focusMoved: LensMove?

    public init() {}

    public init(result: FrameResult) {
        maxilla = Self.jaw(result.maxilla, detected: result.overlay.tags.filter { $0.body == "maxilla" }.count)
        mandible = Self.jaw(result.mandible, detected: result.overlay.tags.filter { $0.body == "mandible" }.count)
        processingMs = result.detectionMs + result.poseMs
        fps = result.fps
        flags = result.flags
        defocused = result.defocused
    }

    private static func jaw(_ pose: BodyResult?, detected: Int) -> Jaw {
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
/// (jaws, timing, frame rate, link, recording), the capture plan's guidance on a line of its own
/// (focus mode planned), then at most one line each for the frame's problem or flags (and one
/// per jaw whose pose uses tags the marker's calibration left nominal), a defocused frame, a
/// focus that moved since it was locked, dropped frames, estimated intrinsics, and the link's
/// problem.
public struct StatusBar: Equatable {
    public let items: [StatusItem]
    /// Whether the link light is shown, and green.
    public let link: (shown: Bool, green: Bool, text: String)
    /// The guidance to the plan's distance and focus, when there is one.
    public let guidance: StatusItem?
    public let notes: [StatusItem]

    public init(
        status: TrackingStatus,
        transmitting: Bool,
        light: AckLight,
        linkProblem: String?,
        recording: Bool,
        recordedFrames: UInt64,
        now: Double,
        guidance: CaptureGuidance? = nil
    ) {
        // A defocused frame gives no trustworthy pose: never shown as good.
        let good = { (jaw: TrackingStatus.Jaw) -> StatusTone in jaw.solved && !status.defocused ? .good : .warning }
        var items = [
            StatusItem(text: "Maxilla \(status.maxilla.tags)", tone: good(status.maxilla)),
            StatusItem(text: "Mandible \(status.mandible.tags)", tone: good(status.mandible)),
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
        self.guidance = guidance.map { StatusItem(text: Self.sentence($0.message), tone: Self.tone(of: $0.kind)) }
        var notes: [StatusItem] = []
        if let problem = status.problem {
            notes.append(StatusItem(text: problem, tone: .problem))
        } else if !status.flags.isEmpty {
            notes.append(StatusItem(text: status.flags.joined(separator: ", "), tone: .warning))
            notes += Self.uncalibratedNotes(status.flags)
        }
        if status.defocused, guidance?.kind != .outOfFocus {
            notes.append(StatusItem(text: "The markers are out of focus: this frame gives no jaw pose.", tone: .problem))
        }
        if let moved = status.focusMoved {
            notes.append(StatusItem(text: String(
                format: "Focus moved (lens at %.2f, locked at %.2f): the focal length changed with it.",
                moved.lensPosition, moved.lockedAt
            ), tone: .problem))
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

    /// The colour of a guidance: ready is good, holding still while focus locks is normal, too
    /// close or too far a warning, out of focus (nothing measured) a problem.
    public static func tone(of kind: GuidanceKind) -> StatusTone {
        switch kind {
        case .ready: return .good
        case .holdStill: return .normal
        case .noMarkers, .tooClose, .tooFar: return .warning
        case .outOfFocus: return .problem
        }
    }

    /// The library's lower-case phrase as a sentence: its first letter upper-case ("too close:
    /// …" → "Too close: …").
    public static func sentence(_ text: String) -> String {
        guard let first = text.first else {
            return text
        }
        return first.uppercased() + text.dropFirst()
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
        a.items == b.items && a.guidance == b.guidance && a.notes == b.notes && a.link.shown == b.link.shown
            && a.link.green == b.link.green && a.link.text == b.link.text
    }
}
