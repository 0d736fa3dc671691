import Foundation
import JawTrackCore

/// Where the marker calibration screen is.
public enum CalibrationPhase: Equatable {
    /// Not shown.
    case closed
    /// Collecting views: every tracked frame is offered to the library.
    case collecting
    /// The library is solving.
    case solving
    /// Solved: the result is shown, to save or to collect more views for.
    case solved
    /// Saved as `marker.json` in Documents; tracking uses it.
    case saved
}

/// The words of the marker calibration screen: titles, buttons and the result table's columns.
public enum CalibrationText {
    public static let title = "Marker calibration"
    public static let open = "Calibrate marker"
    public static let instructions =
        "Turn each marker slowly in front of the camera, a face at a time, so that every tag is seen from "
        + "several angles beside another tag. Keep the markers sharp and well lit."
    public static let solve = "Solve"
    public static let save = "Save"
    public static let addViews = "Add views"
    public static let startOver = "Start over"
    public static let close = "Close"
    public static let solving = "Solving…"
    public static let replaceTitle = "Replace marker.json?"
    public static let replaceText =
        "Documents already holds a marker.json (an earlier calibration, or a file copied in). Tracking uses that "
        + "file; replace it with this calibration?"
    public static let replace = "Replace"
    public static let cancel = "Cancel"
    /// The result table's columns.
    public static let columns = ["Tag", "Views", "Shift x, y (mm)", "Turn (°)", "Error (px)"]
}

/// One row of the result table, as text.
public struct CalibrationRow: Equatable, Identifiable {
    public let id: UInt32
    /// "Upper" or "Lower".
    public let body: String
    public let tag: String
    public let views: String
    public let shift: String
    public let turn: String
    /// Before → after, or why the tag was left nominal.
    public let error: String
    public let calibrated: Bool

    public init(_ tag: TagCalibrationResult) {
        id = tag.id
        body = CalibrationScreen.jaw(tag.body)
        self.tag = "\(tag.id)"
        views = "\(tag.views)"
        calibrated = tag.calibrated
        if let x = tag.shiftXMm, let y = tag.shiftYMm, let turn = tag.turnDeg,
           let before = tag.rmsBeforePx, let after = tag.rmsAfterPx, tag.calibrated {
            shift = String(format: "%+.2f, %+.2f", x, y)
            self.turn = String(format: "%+.1f", turn)
            error = String(format: "%.2f → %.2f", before, after)
        } else {
            shift = "—"
            self.turn = "—"
            error = "left nominal"
        }
    }

    /// The row as one line.
    public var text: String {
        let seen = views == "1" ? "1 view" : "\(views) views"
        return calibrated
            ? "\(body) tag \(tag): \(seen), shifted \(shift) mm, turned \(turn)°, error \(error) px"
            : "\(body) tag \(tag): \(seen), left nominal"
    }
}

/// Everything the marker calibration screen shows.
public struct CalibrationScreen: Equatable {
    public var phase = CalibrationPhase.closed
    /// Views collected (frames that added a view of a marker).
    public var views: UInt32 = 0
    /// One line per marker: its views, its tags ready and those still needing views.
    public var bodyLines: [String] = []
    /// What the last frame gave, as advice.
    public var hint: String?
    /// Whether Solve can calibrate something, and the sentence about it.
    public var canSolve = false
    public var readiness = ""
    /// After solving: one line per marker, the table, what the calibration found, and a warning
    /// about the camera when the views contradict its focal length.
    public var summary: [String] = []
    public var rows: [CalibrationRow] = []
    public var findings: [String] = []
    public var warning: String?
    /// Asks before replacing the `marker.json` in Documents.
    public var confirmReplace = false
    /// The alert on the calibration screen, if any.
    public var message: UserMessage?

    public init() {}

    public var isOpen: Bool { phase != .closed }
    public var canSave: Bool { phase == .solved }
    public var canAddViews: Bool { phase == .solved }

    /// A body's name in a table: "Upper" or "Lower".
    public static func jaw(_ body: String) -> String {
        body == "maxilla" ? "Upper" : (body == "mandible" ? "Lower" : body)
    }

    /// The progress in words.
    public mutating func show(_ progress: CalibrationProgress) {
        views = progress.views
        bodyLines = progress.bodies.map { Self.line($0, minViews: progress.minViews) }
        hint = Self.hint(progress.bodies)
        canSolve = progress.canSolve
        readiness = Self.readiness(progress)
    }

    /// "1 view", "3 views".
    static func views(_ n: UInt32) -> String {
        n == 1 ? "1 view" : "\(n) views"
    }

    static func line(_ body: BodyViews, minViews: UInt32) -> String {
        let head = "\(jaw(body.body)) marker: \(views(body.views)), \(body.tagsReady) of \(body.tagsTotal) tags ready"
        guard !body.needsViews.isEmpty else {
            return head + "."
        }
        return head + "; still needing views: tags " + body.needsViews.map(String.init).joined(separator: ", ") + "."
    }

    static func hint(_ bodies: [BodyViews]) -> String? {
        let outcomes = bodies.compactMap(\.last)
        if outcomes.isEmpty {
            return nil
        }
        if outcomes.contains(.added) {
            return "View added: keep turning."
        }
        if outcomes.contains(.notTracked) {
            return "A marker shows tags but is not tracked: hold it steadier, in good light."
        }
        if outcomes.contains(.sameView) {
            return "Seen from here already: turn the marker further."
        }
        return "Turn a marker so that two faces or more face the camera at once."
    }

    static func readiness(_ progress: CalibrationProgress) -> String {
        if progress.complete {
            return "Every tag has enough views: ready to solve."
        }
        if progress.canSolve {
            return "Ready to solve. Tags still needing views keep their nominal place; more views calibrate them too."
        }
        return "Not ready: a tag needs \(progress.minViews) views, each from an angle at least "
            + String(format: "%.0f° from the others.", progress.minTurnDeg)
    }

    /// A solve's result in words.
    public mutating func show(_ result: MarkerCalibrationResult, bodiesSeen: [String]) {
        summary = result.bodies.map { body in
            "\(Self.jaw(body.body)) marker: \(Self.views(body.views)); "
                + String(format: "error %.2f px before, %.2f px after; ", body.rmsBeforePx, body.rmsAfterPx)
                + "\(body.tagsCalibrated) of \(body.tagsTotal) tags calibrated."
        }
        for body in bodiesSeen where !result.bodies.contains(where: { $0.body == body }) {
            summary.append("\(Self.jaw(body)) marker: never seen; it keeps the placement it had.")
        }
        rows = result.tags.map(CalibrationRow.init)
        findings = result.findings.map(Self.sentence)
        warning = result.focalWarning.map(Self.sentence)
    }

    /// The library's sentence with a capital and a full stop.
    static func sentence(_ text: String) -> String {
        guard let first = text.first else {
            return text
        }
        let capital = first.uppercased() + text.dropFirst()
        return capital.hasSuffix(".") ? capital : capital + "."
    }
}

/// The marker calibration screen's logic: starts a calibration over the running tracker's
/// marker, shows each frame's progress, solves off the frame queue, saves the calibrated marker
/// as `marker.json` in Documents (asking before replacing one) and has tracking use it. Call it
/// on one thread, as `AppController`, which makes it.
public final class CalibrationController {
    /// Views a tag needs to be calibrated (as `jawtrack calibrate-marker`).
    public static let minViews: UInt32 = 3
    public static let fileName = "marker.json"

    public private(set) var state = CalibrationScreen() {
        didSet { onChange?(state) }
    }
    public var onChange: ((CalibrationScreen) -> Void)?
    /// Where solves run, away from the frames.
    public let queue: DispatchQueue

    private let pipeline: FramePipeline
    private let documents: URL?
    private let deliver: (@escaping () -> Void) -> Void
    /// Has tracking use the marker file just saved; throws when the tracker cannot load it.
    var useSavedMarker: (() throws -> Void)?
    private var calibrator: Calibrator?
    /// Bumped by every opening: a calibration started for an earlier one is not taken.
    private var generation = 0
    /// The bodies of the last progress, to name one a solve never saw.
    private var bodies: [String] = []

    init(
        pipeline: FramePipeline,
        documents: URL?,
        queue: DispatchQueue,
        deliver: @escaping (@escaping () -> Void) -> Void
    ) {
        self.pipeline = pipeline
        self.documents = documents
        self.queue = queue
        self.deliver = deliver
    }

    /// Opens the screen and starts collecting views.
    public func open() {
        calibrator = nil
        generation += 1
        var fresh = CalibrationScreen()
        fresh.phase = .collecting
        fresh.readiness = "Show the markers to the camera."
        state = fresh
        let generation = generation
        pipeline.startMarkerCalibration(minViews: Self.minViews) { [weak self] result in
            self?.deliver { self?.started(result, generation: generation) }
        }
    }

    private func started(_ result: Result<Calibrator, Error>, generation: Int) {
        guard generation == self.generation, state.phase == .collecting else {
            return
        }
        switch result {
        case .success(let calibrator):
            self.calibrator = calibrator
        case .failure(let error):
            state.message = UserMessage(title: CalibrationText.title, text: userText(error))
        }
    }

    /// A frame's progress (from the pipeline's report).
    func show(_ progress: CalibrationProgress) {
        guard state.phase == .collecting else {
            return
        }
        bodies = progress.bodies.map(\.body)
        state.show(progress)
    }

    /// Stops collecting and solves; the result or the library's refusal is shown.
    public func solve() {
        guard state.phase == .collecting, let calibrator else {
            return
        }
        pipeline.feed(calibrator: nil)
        state.phase = .solving
        queue.async { [weak self] in
            let result = Result { try calibrator.solve() }
            self?.deliver { self?.solved(result) }
        }
    }

    private func solved(_ result: Result<MarkerCalibrationResult, Error>) {
        guard state.phase == .solving else {
            return
        }
        switch result {
        case .success(let calibration):
            state.phase = .solved
            state.show(calibration, bodiesSeen: bodies)
        case .failure(let error):
            state.message = UserMessage(title: "Not solved", text: userText(error))
            collect()
        }
    }

    /// After a solve: collects more views for the same calibration (the result is dropped).
    public func addViews() {
        guard state.phase == .solved else {
            return
        }
        collect()
    }

    private func collect() {
        state.phase = .collecting
        state.summary = []
        state.rows = []
        state.findings = []
        state.warning = nil
        pipeline.feed(calibrator: calibrator)
    }

    /// Forgets the views and starts again.
    public func startOver() {
        guard let calibrator, state.phase == .collecting || state.phase == .solved else {
            return
        }
        calibrator.reset()
        collect()
        state.show(calibrator.progress())
        state.hint = nil
    }

    /// Saves the result as `marker.json` in Documents; an existing file is replaced only once
    /// the user said so (`replacing`), after `confirmReplace` asked. Tracking then uses it.
    public func save(replacing: Bool = false) {
        state.confirmReplace = false
        guard state.phase == .solved, let calibrator else {
            return
        }
        guard let documents else {
            state.message = UserMessage(title: "Not saved", text: "The app's Documents folder is not available.")
            return
        }
        let url = documents.appendingPathComponent(Self.fileName)
        if !replacing, FileManager.default.fileExists(atPath: url.path) {
            state.confirmReplace = true
            return
        }
        do {
            try calibrator.save(path: url.path, overwrite: replacing)
        } catch {
            state.message = UserMessage(title: "Not saved", text: userText(error))
            return
        }
        state.phase = .saved
        do {
            try useSavedMarker?()
            state.message = UserMessage(
                title: "Marker saved",
                text: "Saved as marker.json in Files › On My iPhone › JawTrack. Tracking uses it from now on; "
                    + "calibrate the bite again."
            )
        } catch {
            state.message = UserMessage(
                title: "Marker saved",
                text: "Saved as marker.json, but tracking cannot use it: \(userText(error))"
            )
        }
    }

    /// The user would not replace the file.
    public func keepExistingFile() {
        state.confirmReplace = false
    }

    /// Closes the screen; views not saved are dropped.
    public func close() {
        pipeline.feed(calibrator: nil)
        calibrator = nil
        generation += 1
        bodies = []
        state = CalibrationScreen()
    }

    public func dismissMessage() {
        state.message = nil
    }
}
