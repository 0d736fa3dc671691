// Adapts SwiftUI's Form to JawTrackKit's SettingsForm: lays out its choices, ranges, notes (the
// planned focus's, the pairing's) and problems, runs the QR scanner for it, and hands the draft
// to `onSave` (the controller's `save`, which answers with the library's refusal or nil).
import JawTrackCore
import JawTrackKit
import SwiftUI

@MainActor
struct SettingsView: View {
    @Environment(\.dismiss) private var dismiss
    @State private var form: SettingsForm
    @State private var scanning = false
    @State private var saveError: String?
    private let readoutInUse: String?
    private let onSave: (AppSettings) -> String?

    /// `readoutInUse`: where the tracker's readout comes from now (`ScreenState.readout`).
    init(settings: AppSettings, readoutInUse: String?, onSave: @escaping (AppSettings) -> String?) {
        _form = State(initialValue: SettingsForm(settings))
        self.readoutInUse = readoutInUse
        self.onSave = onSave
    }

    var body: some View {
        NavigationStack {
            Form {
                if let problem = form.problem { Text(problem).foregroundColor(.red) }
                Section {
                    picker("Camera", $form.draft.camera, SettingsForm.cameras)
                    picker("Focus", $form.draft.focus, SettingsForm.focusModes)
                    picker("Resolution", $form.draft.resolution, SettingsForm.resolutions).disabled(!form.usesResolution)
                    picker("Frame rate", $form.draft.fps, SettingsForm.frameRates)
                    if form.showsLensPosition { slider("Lens", $form.draft.lensPosition, SettingsForm.lensPosition) }
                    Toggle("Lock exposure and white balance", isOn: $form.draft.exposureLocked)
                    Toggle("BGRA frames (converted, slower)", isOn: $form.draft.bgra)
                } header: {
                    Text("Camera")
                } footer: {
                    if let note = form.focusNote { Text(note) }
                }
                Section {
                    picker("Exposure limit", $form.draft.maxExposureS, SettingsForm.exposureLimits)
                    TextField("Calibrated readout (ms)", text: $form.readoutText).keyboardType(.decimalPad)
                } header: {
                    Text("Motion")
                } footer: {
                    VStack(alignment: .leading, spacing: 4) {
                        Text(SettingsForm.exposureLimitNote)
                        Text(SettingsForm.readoutNote)
                        if let readoutInUse { Text("In use: \(readoutInUse)") }
                    }
                }
                Section("Detector") {
                    picker("Decimation", $form.draft.tracker.decimate, SettingsForm.decimations)
                    slider("Quad sigma", $form.draft.tracker.quadSigma, SettingsForm.quadSigma)
                    stepper($form.draft.tracker.maxHamming, SettingsForm.maxHamming)
                    stepper($form.draft.tracker.threads, SettingsForm.threads)
                    Toggle("Fit edges in linear light", isOn: $form.draft.tracker.linearEdges)
                    Toggle("Search near the markers", isOn: $form.draft.tracker.regionSearch)
                    Toggle("Smooth the pose", isOn: $form.draft.tracker.smooth)
                    Toggle("Refine from every pixel (slow, not live)", isOn: $form.draft.tracker.dense)
                }
                receiver
                Section("Recording") { Toggle("Record the video too (.mov)", isOn: $form.draft.recordVideo) }
            }
            .navigationTitle("Settings")
            .navigationBarTitleDisplayMode(.inline)
            .toolbar {
                ToolbarItem(placement: .cancellationAction) { Button("Cancel") { dismiss() } }
                ToolbarItem(placement: .confirmationAction) { Button("Save") { save() }.disabled(form.problem != nil) }
            }
            .sheet(isPresented: $scanning) {
                QRScannerView(
                    onCode: { text in scanning = false; form.scanned(text) },
                    onFailure: { text in scanning = false; form.scanFailed(text) }
                )
                .ignoresSafeArea()
            }
            .alert("Not saved", isPresented: saveErrorShown, presenting: saveError) { _ in
                Button("OK", role: .cancel) {}
            } message: { text in
                Text(text)
            }
        }
    }

    private var receiver: some View {
        Section {
            TextField("Host, e.g. 192.168.1.20", text: $form.draft.receiverHost)
                .keyboardType(.URL)
                .textInputAutocapitalization(.never)
                .autocorrectionDisabled()
            TextField("UDP port", text: $form.portText).keyboardType(.numberPad)
            TextField("Pairing key (64 hex digits)", text: $form.draft.pairingKey, axis: .vertical)
                .font(.footnote.monospaced())
                .textInputAutocapitalization(.never)
                .autocorrectionDisabled()
            Button { scanning = true } label: { Label("Scan the receiver's QR code", systemImage: "qrcode.viewfinder") }
            if let keyId = form.keyId { LabeledContent("Key id", value: keyId) }
        } header: {
            Text("Receiver")
        } footer: {
            VStack(alignment: .leading, spacing: 4) {
                if let note = form.pairingNote { Text(note) }
                if let problem = form.streamingProblem { Text(problem) }
            }
        }
    }

    private var saveErrorShown: Binding<Bool> {
        Binding(get: { saveError != nil }, set: { shown in if !shown { saveError = nil } })
    }

    private func save() {
        if let error = onSave(form.draft) { saveError = error } else { dismiss() }
    }

    private func picker<Value: Hashable>(_ title: String, _ selection: Binding<Value>, _ choices: [Choice<Value>]) -> some View {
        Picker(title, selection: selection) {
            ForEach(choices, id: \.value) { choice in Text(choice.label).tag(choice.value) }
        }
    }

    private func slider(_ title: String, _ value: Binding<Float>, _ range: NumberRange) -> some View {
        HStack {
            Text(title)
            Slider(value: value, in: range.floats, step: range.floatStep)
            Text(range.text(Double(value.wrappedValue))).monospacedDigit()
        }
    }

    private func stepper(_ value: Binding<UInt32>, _ range: NumberRange) -> some View {
        Stepper(value: value, in: range.counts, step: range.countStep) { Text(range.text(Double(value.wrappedValue))) }
    }
}
