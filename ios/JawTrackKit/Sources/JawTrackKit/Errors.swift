import Foundation
import JawTrackCore

/// A message the app shows in an alert.
public struct UserMessage: Identifiable, Equatable {
    public let id = UUID()
    public let title: String
    public let text: String

    public init(title: String, text: String) {
        self.title = title
        self.text = text
    }

    public static func == (a: UserMessage, b: UserMessage) -> Bool {
        a.title == b.title && a.text == b.text
    }
}

/// A failure of the app's own (camera, files, link), worded for the user.
public struct AppError: Error, LocalizedError, Equatable {
    public let message: String

    public init(message: String) {
        self.message = message
    }

    public var errorDescription: String? { message }
}

/// The text a user should read for `error`. For the library's errors it is the message Rust
/// wrote: the generated `errorDescription` is Swift's reflection of the case, not meant for people.
public func userText(_ error: Error) -> String {
    if let error = error as? JawTrackError {
        switch error {
        case .InvalidSetting(_, let message), .InvalidFrame(let message), .InvalidIntrinsics(let message),
             .InvalidMarker(let message), .InvalidKey(let message), .NotEnoughFrames(_, _, let message),
             .JawMoving(_, _, let message), .Calibration(let message), .InvalidArgument(let message),
             .Io(_, let message), .Link(let message):
            return message
        }
    }
    if let error = error as? AppError {
        return error.message
    }
    return error.localizedDescription
}
