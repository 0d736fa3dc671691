// Adapts SwiftUI to JawTrackKit's ScreenState and AppController: lays out the camera screen
// (preview and overlay, status bar, the capture plan before recording, Record / Transmit /
// Calibrate bite / Calibrate marker / Settings, the alerts; the marker calibration's panel in
// place of the plan and buttons while it is open) and forwards every tap and scene phase to the
// controller.
import JawTrackKit
import SwiftUI

@MainActor
struct ContentView: View {
    @ObservedObject var model: AppModel
    @Environment(\.scenePhase) private var scenePhase
    @State private var showingSettings = false
    /// The naming alert's field.
    @State private var name = ""

    private var state: ScreenState { model.state }
    private var controller: AppController { model.controller }

    var body: some View {
        ZStack {
            PreviewView(session: model.camera.session, overlay: state.overlay, configurationID: state.configurationID)
                .ignoresSafeArea()
            VStack(spacing: 0) {
                StatusBarView(state: state)
                    .frame(maxWidth: .infinity, alignment: .leading)
                    .padding(.horizontal, 8)
                Spacer()
                if model.calibration.isOpen {
                    CalibrationView(screen: model.calibration, controller: controller.markerCalibration)
                } else {
                    if state.showsPlan { plan }
                    controls
                }
            }
        }
        .onAppear { model.start() }
        .onChange(of: scenePhase) { phase in
            controller.phaseChanged(phase == .active ? .active : (phase == .background ? .background : .inactive))
        }
        .onChange(of: state.finishedRecording) { _ in name = state.recordingName }
        .sheet(isPresented: $showingSettings, onDismiss: { controller.settingsClosed() }) {
            SettingsView(settings: controller.settings.settings, readoutInUse: state.readout?.source) { controller.save($0) }
        }
        .alert(state.message?.title ?? "", isPresented: messageShown, presenting: state.message) { _ in
            Button("OK", role: .cancel) {}
        } message: { message in
            Text(message.text)
        }
    }

    /// The capture plan, shown before recording: where to hold the phone and how the camera is
    /// set, then its notes (figures assumed, a target out of reach).
    private var plan: some View {
        VStack(alignment: .leading, spacing: 4) {
            ForEach(state.planLines.indices, id: \.self) { i in
                Text(state.planLines[i])
                    .font(i == 0 ? .footnote : .caption)
                    .foregroundColor(i == 0 ? .white : .yellow)
            }
        }
        .frame(maxWidth: .infinity, alignment: .leading)
        .padding(8)
        .background(Color.black.opacity(0.55))
        .clipShape(RoundedRectangle(cornerRadius: 8))
        .padding(.horizontal, 8)
        .padding(.bottom, 6)
    }

    private var controls: some View {
        HStack(spacing: 10) {
            Button { controller.toggleRecording() } label: {
                Label(state.isRecording ? "Stop" : "Record", systemImage: state.isRecording ? "stop.circle.fill" : "record.circle")
            }
            .tint(state.isRecording ? Color.red : Color.accentColor)
            .alert("Name the recording", isPresented: naming, presenting: state.finishedRecording) { _ in
                TextField("Name", text: $name)
                Button("Save") { controller.nameRecording(as: name) }
                Button("Keep the date", role: .cancel) { controller.nameRecording(as: nil) }
            } message: { files in
                Text(AppController.savedText(files))
            }
            Toggle(isOn: Binding(get: { state.isTransmitting }, set: { controller.setTransmitting($0) })) {
                Label("Transmit", systemImage: "antenna.radiowaves.left.and.right")
            }
            .toggleStyle(.button)
            Button { controller.calibrateBite() } label: { Label("Calibrate bite", systemImage: "mouth") }
                .disabled(state.isCalibrating)
            Button { controller.openMarkerCalibration() } label: {
                Label(CalibrationText.open, systemImage: "cube").labelStyle(.iconOnly)
            }
            .disabled(!state.canCalibrateMarker)
            Button {
                controller.settingsOpened()
                showingSettings = true
            } label: {
                Label("Settings", systemImage: "gearshape").labelStyle(.iconOnly)
            }
            .disabled(!state.canOpenSettings)
        }
        .font(.footnote)
        .buttonStyle(.borderedProminent)
        .padding(10)
        .background(.ultraThinMaterial, in: Capsule())
        .padding(.bottom, 8)
    }

    private var messageShown: Binding<Bool> {
        Binding(get: { state.message != nil }, set: { shown in if !shown { controller.dismissMessage() } })
    }

    /// Shown while a stopped recording waits for its name; its buttons name it (or not).
    private var naming: Binding<Bool> { Binding(get: { state.finishedRecording != nil }, set: { _ in }) }
}
