// Adapts SwiftUI's App to JawTrackKit: one window, the camera screen over the AppModel.
import SwiftUI

@main
@MainActor
struct JawTrackApp: App {
    @StateObject private var model = AppModel()

    var body: some Scene { WindowGroup { ContentView(model: model) } }
}
