import Foundation
import JawTrackCore

/// What the focus lock makes of one frame.
public struct FocusStep: Equatable {
    /// The capture plan's guidance for the frame.
    public let guidance: CaptureGuidance
    /// Ask the camera to lock its focus now.
    public let lockNow: Bool
    /// The frame's lens position, when focus is locked and the lens has moved away from where it
    /// was locked (by more than `FocusLock.lensTolerance`): the focal length changed with it.
    public let movedLensPosition: Double?
}

/// The planned capture's focus, frame by frame (focus mode planned): every frame's guidance
/// comes from the capture plan (`CapturePlanner.guide`) with the frame's depth and defocus, and
/// with focus locked or not. Before the lock the camera focuses continuously on the centre; once
/// the guidance has said "hold still" for `steadyFrames` consecutive frames, none of them taken
/// while the camera said it was adjusting its focus, the camera is asked to lock its focus where
/// it is (once; again only after a failure is cleared by a new session). Once locked, the lens
/// position focus was locked at is kept, frames are guided as locked, and a frame whose lens
/// position is more than `lensTolerance` from it is said to have moved. A new camera session,
/// new settings or a new configuration start a new `FocusLock`.
public struct FocusLock {
    /// Consecutive "hold still" frames before focus is locked: a third of a second at 60 fps,
    /// two thirds at 30, time for continuous autofocus to settle at the distance.
    public static let steadyFrames = 20
    /// How far (lens position, 0 near – 1 far) a frame's lens may be from where focus was locked
    /// before focus is said to have moved.
    public static let lensTolerance = 0.02

    public let planner: CapturePlanner
    public let choice: PlanChoice
    /// Where focus was locked (nil: not yet).
    public private(set) var lockedLensPosition: Double?
    /// A lock asked of the camera and not answered yet.
    public private(set) var isLocking = false
    /// The camera could not lock its focus: not asked again in this session.
    public private(set) var lockFailed = false
    /// Consecutive frames guided "hold still" so far.
    public private(set) var steadyRun = 0

    public init(planner: CapturePlanner) {
        self.planner = planner
        choice = planner.choice()
    }

    public var isLocked: Bool { lockedLensPosition != nil }

    /// One frame: its markers' depth (mm, nil when none was solved), whether a body was too
    /// blurred to trust, its lens position and whether the camera was adjusting its focus, when
    /// the camera said.
    public mutating func frame(depthMm: Double?, defocused: Bool, lensPosition: Double?, adjustingFocus: Bool?) -> FocusStep {
        let guidance = planner.guide(depthMm: depthMm, focusLocked: isLocked, defocused: defocused)
        if let locked = lockedLensPosition {
            let moved = lensPosition.flatMap { abs($0 - locked) > Self.lensTolerance ? $0 : nil }
            return FocusStep(guidance: guidance, lockNow: false, movedLensPosition: moved)
        }
        steadyRun = guidance.kind == .holdStill && adjustingFocus != true ? steadyRun + 1 : 0
        let lockNow = steadyRun >= Self.steadyFrames && !isLocking && !lockFailed
        if lockNow {
            isLocking = true
        }
        return FocusStep(guidance: guidance, lockNow: lockNow, movedLensPosition: nil)
    }

    /// The camera locked its focus at `lensPosition`.
    public mutating func locked(at lensPosition: Double) {
        isLocking = false
        lockedLensPosition = lensPosition
    }

    /// The camera could not lock its focus.
    public mutating func failed() {
        isLocking = false
        lockFailed = true
        steadyRun = 0
    }

    /// What to say when recording is asked for before focus is locked.
    public var holdText: String {
        String(
            format: "Hold the phone about %.0f cm from the markers until focus locks; recording starts once it has.",
            choice.distanceMm / 10
        )
    }
}
