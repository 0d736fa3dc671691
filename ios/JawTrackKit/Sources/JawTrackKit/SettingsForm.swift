import Foundation
import JawTrackCore

/// A choice in a picker: the value and its label.
public struct Choice<Value: Hashable>: Equatable {
    public let value: Value
    public let label: String
}

/// A number picked on a slider or stepper: its range, step and how it is printed.
public struct NumberRange: Equatable {
    public let range: ClosedRange<Double>
    public let step: Double
    public let format: String
}

/// The settings screen's content and logic, for a copy of the settings being edited: what each
/// control offers, what is wrong (the library's `validateAppSettings`, its message shown as
/// is), what is still missing to transmit, and the pairing flows (QR code or typed key, read by
/// `parsePairing` / `pairingKeyId`). The SwiftUI view only lays it out.
public struct SettingsForm {
    public var draft: AppSettings
    /// What the last scan did, for the receiver section's footer.
    public private(set) var pairingNote: String?

    public init(_ settings: AppSettings) {
        draft = settings
    }

    public static let cameras = [
        Choice(value: Camera.backWide, label: "Back wide"),
        Choice(value: Camera.backTele, label: "Back telephoto"),
        Choice(value: Camera.front, label: "Front"),
    ]
    public static let resolutions = [
        Choice(value: Resolution.hd720, label: "720p"),
        Choice(value: Resolution.hd1080, label: "1080p"),
        Choice(value: Resolution.uhd4k, label: "4K"),
    ]
    public static let frameRates = [Choice(value: UInt32(30), label: "30 fps"), Choice(value: UInt32(60), label: "60 fps")]
    /// Planned first: the default, and what a phone that cannot focus close needs.
    public static let focusModes = [
        Choice(value: FocusMode.planned, label: "Planned"),
        Choice(value: FocusMode.auto, label: "Auto"),
        Choice(value: FocusMode.manual, label: "Manual"),
    ]
    public static let decimations = [Float(1), 1.5, 2, 3, 4].map { Choice(value: $0, label: String(format: "%g", Double($0))) }
    public static let lensPosition = NumberRange(range: 0...1, step: 0.01, format: "%.2f")
    public static let quadSigma = NumberRange(range: 0...0.8, step: 0.1, format: "%.1f")
    public static let maxHamming = NumberRange(range: 0...2, step: 1, format: "Max Hamming distance: %.0f")
    public static let threads = NumberRange(range: 1...8, step: 1, format: "Threads: %.0f")
    /// Exposure caps (s): short keeps a chewing jaw sharp, long keeps a dim room's noise down.
    public static let exposureLimits = [
        Choice(value: 0.001, label: "1 ms"),
        Choice(value: 0.002, label: "2 ms (sharp while chewing)"),
        Choice(value: 0.004, label: "4 ms"),
        Choice(value: 0.008, label: "8 ms"),
        Choice(value: 0.0, label: "None (the camera's own)"),
    ]
    public static let exposureLimitNote =
        "Automatic exposure stays at or below the limit while the room is bright enough, and may go up to 4× it in a dim room. Longer exposures smear moving tags; shorter ones are noisier."
    public static let plannedFocusNote =
        "Planned: the app plans the format, zoom and distance for this camera (it cannot focus closer than its "
        + "nearest focus), guides you to that distance and locks the focus there before recording. The resolution "
        + "setting is not used while focus is planned."
    public static let readoutNote =
        "Rows are read one after another; the tracker needs how long that takes to solve both jaws at one instant. Leave empty to use the phone's published figure; enter the readout `jawtrack calibrate-camera` measured to use it instead."

    /// Whether the lens position control is shown.
    public var showsLensPosition: Bool { draft.focus == .manual }
    /// Whether the resolution setting is used: not while focus is planned (the plan chooses).
    public var usesResolution: Bool { draft.focus != .planned }
    /// What the camera section's footer says about the focus mode chosen.
    public var focusNote: String? { draft.focus == .planned ? Self.plannedFocusNote : nil }

    /// The first problem of the settings (nil: they can be saved).
    public var problem: String? {
        Self.problem { try validateAppSettings(settings: draft, streaming: false) }
    }

    /// What is still missing to transmit (host, port, key), or nil.
    public var streamingProblem: String? {
        Self.problem { try validateAppSettings(settings: draft, streaming: true) }.map { "To transmit: \($0)" }
    }

    /// The typed or scanned key's id, when it is a key.
    public var keyId: String? {
        draft.pairingKey.isEmpty ? nil : try? pairingKeyId(text: draft.pairingKey)
    }

    /// The port as typed: digits only, "" for none; more than five digits or above 65535 is
    /// kept as typed so the library names the problem.
    public var portText: String {
        get { draft.receiverPort == 0 ? "" : String(draft.receiverPort) }
        set { draft.receiverPort = UInt32(String(newValue.filter { ("0"..."9").contains($0) }.prefix(9))) ?? 0 }
    }

    /// The calibrated readout as typed, in ms; "" for none (the phone's published figure). What
    /// is not a number is kept as not-a-number so that the library names the problem.
    public var readoutText: String {
        get { draft.calibratedReadoutS.map { String(format: "%g", $0 * 1e3) } ?? "" }
        set {
            let typed = newValue.trimmingCharacters(in: .whitespaces).replacingOccurrences(of: ",", with: ".")
            draft.calibratedReadoutS = typed.isEmpty ? nil : (Double(typed).map { $0 / 1e3 } ?? .nan)
        }
    }

    /// A scanned QR code: the key, and the host and port when it names them.
    public mutating func scanned(_ text: String) {
        do {
            let pairing = try parsePairing(text: text)
            draft.pairingKey = pairing.keyHex
            if let host = pairing.host {
                draft.receiverHost = host
            }
            if let port = pairing.port {
                draft.receiverPort = port
            }
            pairingNote = "Paired: key id \(pairing.keyId)."
        } catch {
            pairingNote = "Not a JawTrack pairing code: \(userText(error))"
        }
    }

    /// The scanner could not run (no camera, permission refused).
    public mutating func scanFailed(_ text: String) {
        pairingNote = text
    }

    private static func problem(_ check: () throws -> Void) -> String? {
        do {
            try check()
            return nil
        } catch {
            return userText(error)
        }
    }
}

extension NumberRange {
    /// The range for a slider over a `Float` setting.
    public var floats: ClosedRange<Float> { Float(range.lowerBound)...Float(range.upperBound) }
    public var floatStep: Float { Float(step) }
    /// The range for a stepper over a counting (`UInt32`) setting.
    public var counts: ClosedRange<UInt32> { UInt32(range.lowerBound)...UInt32(range.upperBound) }
    public var countStep: Int { Int(step) }

    /// `value` printed with the range's format.
    public func text(_ value: Double) -> String {
        String(format: format, value)
    }
}
