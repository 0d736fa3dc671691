import Foundation
import JawTrackCore

/// A message the app shows in an alert.
struct UserMessage: Identifiable {
    let id = UUID()
    let title: String
    let text: String
}

/// A failure of the app's own (camera, files, link), worded for the user.
struct AppError: Error, LocalizedError {
    let message: String

    var errorDescription: String? { message }
}

/// The text a user should read for `error`. For the library's errors it is the message Rust
/// wrote: the generated `errorDescription` is Swift's reflection of the case, not meant for people.
func userText(_ error: Error) -> String {
    if let error = error as? JawTrackError {
        switch error {
        case .InvalidSetting(_, let message), .InvalidFrame(let message), .InvalidIntrinsics(let message),
             .InvalidMarker(let message), .InvalidKey(let message), .NotEnoughFrames(_, _, let message),
             .InvalidArgument(let message), .Io(_, let message), .Link(let message):
            return message
        }
    }
    return error.localizedDescription
}
