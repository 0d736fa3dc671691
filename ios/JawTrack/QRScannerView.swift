// Adapts AVCaptureMetadataOutput (.qr) to JawTrackKit's SettingsForm pairing: a capture session
// of its own hands the first code's text to `onCode` (`form.scanned`), or why it cannot scan to
// `onFailure` (`form.scanFailed`). The main camera is stopped while settings are open.
import AVFoundation
import JawTrackCore
import JawTrackKit
import SwiftUI

@MainActor
struct QRScannerView: UIViewRepresentable {
    let onCode: (String) -> Void
    let onFailure: (String) -> Void

    func makeCoordinator() -> QRCodeReader { QRCodeReader(onCode: onCode, onFailure: onFailure) }

    func makeUIView(context: Context) -> PreviewUIView {
        context.coordinator.start()
        return PreviewUIView(session: context.coordinator.session, gravity: .resizeAspectFill)
    }

    func updateUIView(_ uiView: PreviewUIView, context: Context) {}

    static func dismantleUIView(_ uiView: PreviewUIView, coordinator: QRCodeReader) { coordinator.stop() }
}

/// The scanner's session, configured and run on its own queue; codes arrive on the main queue.
final class QRCodeReader: NSObject, AVCaptureMetadataOutputObjectsDelegate {
    let session = AVCaptureSession()
    private let queue = DispatchQueue(label: "org.jawtrack.qr")
    private let onCode: (String) -> Void
    private let onFailure: (String) -> Void
    private var delivered = false

    init(onCode: @escaping (String) -> Void, onFailure: @escaping (String) -> Void) {
        self.onCode = onCode
        self.onFailure = onFailure
    }

    func start() {
        queue.async { [self] in
            do {
                try configure()
                session.startRunning()
            } catch {
                let text = userText(error)
                DispatchQueue.main.async { self.onFailure(text) }
            }
        }
    }

    func stop() { queue.async { [self] in session.stopRunning() } }

    private func configure() throws {
        guard let device = AVCaptureDevice.default(.builtInWideAngleCamera, for: .video, position: .back) else {
            throw CameraPlanner.missingCamera(.backWide)
        }
        let input = try AVCaptureDeviceInput(device: device)
        let output = AVCaptureMetadataOutput()
        session.beginConfiguration()
        defer { session.commitConfiguration() }
        guard session.canAddInput(input), session.canAddOutput(output) else { throw PlatformText.scannerUnavailable }
        session.addInput(input)
        session.addOutput(output)
        guard output.availableMetadataObjectTypes.contains(.qr) else { throw PlatformText.qrUnsupported }
        output.setMetadataObjectsDelegate(self, queue: .main)
        output.metadataObjectTypes = [.qr]
    }

    func metadataOutput(_ output: AVCaptureMetadataOutput, didOutput objects: [AVMetadataObject], from connection: AVCaptureConnection) {
        let codes = objects.compactMap { $0 as? AVMetadataMachineReadableCodeObject }
        guard !delivered, let text = codes.first(where: { $0.type == .qr })?.stringValue else { return }
        delivered = true
        onCode(text)
    }
}
