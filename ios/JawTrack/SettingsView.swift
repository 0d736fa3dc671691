import JawTrackCore
import SwiftUI

/// The settings screen. It edits a copy; what is valid is the library's call
/// (`validateAppSettings`, whose message is shown as is), and a scanned or typed pairing is read
/// by `parsePairing`. Save hands the copy to `onSave`, which answers with an error text or nil.
@MainActor
struct SettingsView: View {
    @Environment(\.dismiss) private var dismiss
    @State private var draft: AppSettings
    @State private var scanning = false
    @State private var pairingNote: String?
    @State private var saveError: String?
    private let onSave: (AppSettings) -> String?

    private static let decimations: [Float] = [1, 1.5, 2, 3, 4]

    init(initial: AppSettings, onSave: @escaping (AppSettings) -> String?) {
        _draft = State(initialValue: initial)
        self.onSave = onSave
    }

    var body: some View {
        NavigationStack {
            Form {
                if let problem {
                    Section {
                        Text(verbatim: problem)
                            .foregroundColor(.red)
                    }
                }
                cameraSection
                detectorSection
                receiverSection
                Section("Recording") {
                    Toggle("Record the video too (.mov)", isOn: $draft.recordVideo)
                }
            }
            .navigationTitle("Settings")
            .navigationBarTitleDisplayMode(.inline)
            .toolbar {
                ToolbarItem(placement: .cancellationAction) {
                    Button("Cancel") { dismiss() }
                }
                ToolbarItem(placement: .confirmationAction) {
                    Button("Save") { save() }
                        .disabled(problem != nil)
                }
            }
            .sheet(isPresented: $scanning) {
                scanner
            }
            .alert("Not saved", isPresented: saveErrorShown, presenting: saveError) { _ in
                Button("OK", role: .cancel) {}
            } message: { text in
                Text(verbatim: text)
            }
        }
    }

    private var cameraSection: some View {
        Section("Camera") {
            Picker("Camera", selection: $draft.camera) {
                Text("Back wide").tag(JawTrackCore.Camera.backWide)
                Text("Back telephoto").tag(JawTrackCore.Camera.backTele)
                Text("Front").tag(JawTrackCore.Camera.front)
            }
            Picker("Resolution", selection: $draft.resolution) {
                Text("720p").tag(Resolution.hd720)
                Text("1080p").tag(Resolution.hd1080)
                Text("4K").tag(Resolution.uhd4k)
            }
            Picker("Frame rate", selection: $draft.fps) {
                Text("30 fps").tag(UInt32(30))
                Text("60 fps").tag(UInt32(60))
            }
            Picker("Focus", selection: $draft.focus) {
                Text("Auto").tag(FocusMode.auto)
                Text("Manual").tag(FocusMode.manual)
            }
            if draft.focus == .manual {
                HStack {
                    Text("Lens")
                    Slider(value: $draft.lensPosition, in: 0...1)
                    Text(verbatim: String(format: "%.2f", draft.lensPosition))
                        .monospacedDigit()
                }
            }
            Toggle("Lock exposure", isOn: $draft.exposureLocked)
            Toggle("BGRA frames (converted, slower)", isOn: $draft.bgra)
        }
    }

    private var detectorSection: some View {
        Section("Detector") {
            Picker("Decimation", selection: $draft.tracker.decimate) {
                ForEach(Self.decimations, id: \.self) { value in
                    Text(verbatim: String(format: "%g", Double(value))).tag(value)
                }
            }
            HStack {
                Text("Quad sigma")
                Slider(value: $draft.tracker.quadSigma, in: 0...0.8, step: 0.1)
                Text(verbatim: String(format: "%.1f", draft.tracker.quadSigma))
                    .monospacedDigit()
            }
            Stepper(value: $draft.tracker.maxHamming, in: 0...2) {
                Text(verbatim: "Max Hamming distance: \(draft.tracker.maxHamming)")
            }
            Stepper(value: $draft.tracker.threads, in: 1...8) {
                Text(verbatim: "Threads: \(draft.tracker.threads)")
            }
            Toggle("Fit edges in linear light", isOn: $draft.tracker.linearEdges)
            Toggle("Search near the markers", isOn: $draft.tracker.regionSearch)
            Toggle("Smooth the pose", isOn: $draft.tracker.smooth)
        }
    }

    private var receiverSection: some View {
        Section {
            TextField("Host, e.g. 192.168.1.20", text: $draft.receiverHost)
                .keyboardType(.URL)
                .textInputAutocapitalization(.never)
                .autocorrectionDisabled()
            TextField("UDP port", text: portText)
                .keyboardType(.numberPad)
            TextField("Pairing key (64 hex digits)", text: $draft.pairingKey, axis: .vertical)
                .font(.footnote.monospaced())
                .textInputAutocapitalization(.never)
                .autocorrectionDisabled()
            Button {
                scanning = true
            } label: {
                Label("Scan the receiver's QR code", systemImage: "qrcode.viewfinder")
            }
            if let keyId {
                LabeledContent("Key id", value: keyId)
            }
        } header: {
            Text("Receiver")
        } footer: {
            VStack(alignment: .leading, spacing: 4) {
                if let pairingNote {
                    Text(verbatim: pairingNote)
                }
                if let streamingProblem {
                    Text(verbatim: "To transmit: \(streamingProblem)")
                }
            }
        }
    }

    private var scanner: some View {
        NavigationStack {
            QRScannerView(onCode: { text in scanned(text) }, onFailure: { text in
                scanning = false
                pairingNote = text
            })
            .ignoresSafeArea()
            .navigationTitle("Scan the pairing code")
            .navigationBarTitleDisplayMode(.inline)
            .toolbar {
                ToolbarItem(placement: .cancellationAction) {
                    Button("Cancel") { scanning = false }
                }
            }
        }
    }

    /// The first settings problem (nil: the settings can be saved).
    private var problem: String? {
        do {
            try validateAppSettings(settings: draft, streaming: false)
            return nil
        } catch {
            return userText(error)
        }
    }

    /// What is still missing for transmitting (host, port, key).
    private var streamingProblem: String? {
        do {
            try validateAppSettings(settings: draft, streaming: true)
            return nil
        } catch {
            return userText(error)
        }
    }

    private var keyId: String? {
        guard !draft.pairingKey.isEmpty else {
            return nil
        }
        return try? pairingKeyId(text: draft.pairingKey)
    }

    private var portText: Binding<String> {
        Binding(
            get: { draft.receiverPort == 0 ? "" : String(draft.receiverPort) },
            set: { text in draft.receiverPort = UInt32(text.filter { ("0"..."9").contains($0) }) ?? 0 }
        )
    }

    private var saveErrorShown: Binding<Bool> {
        Binding(get: { saveError != nil }, set: { shown in
            if !shown {
                saveError = nil
            }
        })
    }

    private func scanned(_ text: String) {
        scanning = false
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

    private func save() {
        if let error = onSave(draft) {
            saveError = error
        } else {
            dismiss()
        }
    }
}
