import SwiftUI

/// The app: one window, the camera screen.
@main
@MainActor
struct JawTrackApp: App {
    @StateObject private var model = AppModel()

    var body: some Scene {
        WindowGroup {
            ContentView(model: model)
        }
    }
}
