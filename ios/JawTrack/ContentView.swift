import JawTrackCore
import SwiftUI

/// The camera screen: the preview with the overlay, the status bar, and the controls (record,
/// transmit, calibrate the bite, settings).
@MainActor
struct ContentView: View {
    @ObservedObject var model: AppModel
    @Environment(\.scenePhase) private var scenePhase
    @State private var showingSettings = false

    var body: some View {
        ZStack {
            PreviewView(session: model.camera.session, overlay: model.overlay, configurationID: model.configurationID)
                .ignoresSafeArea()
            VStack(spacing: 0) {
                StatusBarView(
                    status: model.status,
                    isTransmitting: model.isTransmitting,
                    lastAckAt: model.lastAckAt,
                    lastAck: model.lastAck,
                    linkProblem: model.linkProblem,
                    isRecording: model.isRecording,
                    recordedFrames: model.recordedFrames
                )
                .frame(maxWidth: .infinity, alignment: .leading)
                .padding(.horizontal, 8)
                Spacer()
                controls
            }
        }
        .onAppear { model.start() }
        .onChange(of: scenePhase) { phase in
            model.scenePhaseChanged(phase)
        }
        .sheet(isPresented: $showingSettings, onDismiss: { model.settingsClosed() }) {
            SettingsView(initial: model.settingsStore.settings) { model.save($0) }
        }
        .alert(model.message?.title ?? "", isPresented: messageShown, presenting: model.message) { _ in
            Button("OK", role: .cancel) {}
        } message: { message in
            Text(verbatim: message.text)
        }
    }

    private var controls: some View {
        HStack(spacing: 10) {
            Button {
                model.toggleRecording()
            } label: {
                Label(model.isRecording ? "Stop" : "Record", systemImage: model.isRecording ? "stop.circle.fill" : "record.circle")
            }
            .tint(model.isRecording ? Color.red : Color.accentColor)
            .alert("Name the recording", isPresented: $model.isNamingRecording, presenting: model.finishedRecording) { files in
                TextField("Name", text: $model.recordingName)
                Button("Save") { model.nameRecording(files, as: model.recordingName) }
                Button("Keep the date", role: .cancel) { model.nameRecording(files, as: nil) }
            } message: { files in
                Text(verbatim: files.video == nil
                    ? "Saved in Files › On My iPhone › JawTrack."
                    : "Saved with its video in Files › On My iPhone › JawTrack.")
            }

            Toggle(isOn: transmitting) {
                Label("Transmit", systemImage: "antenna.radiowaves.left.and.right")
            }
            .toggleStyle(.button)

            Button {
                model.calibrateBite()
            } label: {
                Label("Calibrate bite", systemImage: "mouth")
            }
            .disabled(model.isCalibrating)

            Button {
                model.settingsOpened()
                showingSettings = true
            } label: {
                Label("Settings", systemImage: "gearshape")
                    .labelStyle(.iconOnly)
            }
            .disabled(model.isRecording)
        }
        .font(.footnote)
        .buttonStyle(.borderedProminent)
        .padding(10)
        .background(.ultraThinMaterial, in: Capsule())
        .padding(.bottom, 8)
    }

    private var transmitting: Binding<Bool> {
        Binding(get: { model.isTransmitting }, set: { model.setTransmitting($0) })
    }

    private var messageShown: Binding<Bool> {
        Binding(get: { model.message != nil }, set: { shown in
            if !shown {
                model.message = nil
            }
        })
    }
}
