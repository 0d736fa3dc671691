import AVFoundation
import SwiftUI
import UIKit

/// Scans the pairing QR code the receiver shows (`jawtrack receive --qr`) with a capture session
/// of its own and an `AVCaptureMetadataOutput` for `.qr`; hands the first code's text back,
/// once. Reading the text is the library's job (`parsePairing`). The main camera is stopped
/// while the settings screen is open, so the two sessions never compete.
@MainActor
struct QRScannerView: UIViewRepresentable {
    let onCode: (String) -> Void
    let onFailure: (String) -> Void

    func makeCoordinator() -> QRCodeReader {
        QRCodeReader(onCode: onCode, onFailure: onFailure)
    }

    func makeUIView(context: Context) -> PreviewUIView {
        let view = PreviewUIView(session: context.coordinator.session, overlay: nil, gravity: .resizeAspectFill)
        context.coordinator.start()
        return view
    }

    func updateUIView(_ uiView: PreviewUIView, context: Context) {}

    static func dismantleUIView(_ uiView: PreviewUIView, coordinator: QRCodeReader) {
        coordinator.stop()
    }
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

    func stop() {
        queue.async { [self] in
            if session.isRunning {
                session.stopRunning()
            }
        }
    }

    private func configure() throws {
        guard let device = AVCaptureDevice.default(.builtInWideAngleCamera, for: .video, position: .back) else {
            throw AppError(message: "This iPhone has no back camera to scan with.")
        }
        let input = try AVCaptureDeviceInput(device: device)
        let output = AVCaptureMetadataOutput()
        session.beginConfiguration()
        defer { session.commitConfiguration() }
        guard session.canAddInput(input), session.canAddOutput(output) else {
            throw AppError(message: "The camera cannot scan now.")
        }
        session.addInput(input)
        session.addOutput(output)
        guard output.availableMetadataObjectTypes.contains(.qr) else {
            throw AppError(message: "This camera cannot read QR codes.")
        }
        output.setMetadataObjectsDelegate(self, queue: .main)
        output.metadataObjectTypes = [.qr]
    }

    func metadataOutput(
        _ output: AVCaptureMetadataOutput,
        didOutput metadataObjects: [AVMetadataObject],
        from connection: AVCaptureConnection
    ) {
        guard !delivered else {
            return
        }
        for object in metadataObjects {
            if let code = object as? AVMetadataMachineReadableCodeObject, code.type == .qr, let text = code.stringValue {
                delivered = true
                onCode(text)
                return
            }
        }
    }
}
