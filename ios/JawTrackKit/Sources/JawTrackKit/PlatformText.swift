import Foundation
import JawTrackCore

/// The app's words for what the platform refused (camera, QR scanner, movie writer, network,
/// Keychain); the Apple layer throws or shows these as they are.
public enum PlatformText {
    public static func cameraBusy(_ camera: Camera) -> AppError {
        AppError(message: "The \(CameraPlanner.title(of: camera)) camera cannot be used now.")
    }

    public static var framesUnavailable: AppError {
        AppError(message: "The camera's frames cannot be read now.")
    }

    public static func pixelFormatUnavailable(_ layout: PixelLayout) -> AppError {
        let name = layout == .luma ? "420f" : "BGRA"
        return AppError(message: "This camera does not deliver \(name) frames.")
    }

    public static func noManualFocus(_ camera: Camera) -> AppError {
        AppError(message: "The \(CameraPlanner.title(of: camera)) camera has no manual focus; choose auto.")
    }

    public static func focusLockUnsupported(_ camera: Camera) -> AppError {
        AppError(message: "The \(CameraPlanner.title(of: camera)) camera cannot lock its focus.")
    }

    /// Why focus was not locked, and what to do: in focus mode planned, recording waits for it.
    public static func focusNotLocked(_ error: Error) -> String {
        var text = userText(error).trimmingCharacters(in: .whitespacesAndNewlines)
        if !text.hasSuffix(".") {
            text += "."
        }
        return text + " Focus mode Planned records only with the focus locked: leave the app and come back to try "
            + "again, or choose Auto focus in Settings."
    }

    /// The camera's formats are not those it described (the configuration asked for one that is
    /// not there).
    public static var formatUnavailable: AppError {
        AppError(
            message: "The camera's format changed while it was being set up; open Settings and close them to try again."
        )
    }

    public static var exposureLockUnsupported: AppError {
        AppError(message: "This camera cannot lock its exposure.")
    }

    /// Why exposure and white balance were not locked.
    public static func exposureNotLocked(_ error: Error) -> String {
        "The exposure could not be locked: \(userText(error))"
    }

    public static var scannerUnavailable: AppError {
        AppError(message: "The camera cannot scan now.")
    }

    public static var qrUnsupported: AppError {
        AppError(message: "This camera cannot read QR codes.")
    }

    public static var videoInputRefused: AppError {
        AppError(message: "The video cannot be written with this camera format.")
    }

    /// The movie writer stopped without an error of its own.
    public static var videoUnfinished: AppError {
        AppError(message: "The movie writer stopped without saying why.")
    }

    public static func invalidPort(_ port: UInt16) -> AppError {
        AppError(message: "Receiver port \(port) is not a UDP port (1–65535).")
    }

    /// A Keychain failure: the system's text for `status`, or its number.
    public static func keychain(status: Int32, text: String?) -> AppError {
        AppError(message: "Keychain: " + (text ?? "error \(status)"))
    }
}
