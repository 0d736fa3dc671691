import AVFoundation
import SwiftUI
import UIKit

/// The camera preview for SwiftUI: an `AVCaptureVideoPreviewLayer`, with the overlay's layers
/// above it when given.
@MainActor
struct PreviewView: UIViewRepresentable {
    let session: AVCaptureSession
    let overlay: OverlayRenderer?
    var gravity: AVLayerVideoGravity = .resizeAspect
    /// Changes when the camera is reconfigured, so the preview's orientation is set again.
    var configurationID = 0

    func makeUIView(context: Context) -> PreviewUIView {
        PreviewUIView(session: session, overlay: overlay, gravity: gravity)
    }

    func updateUIView(_ uiView: PreviewUIView, context: Context) {
        uiView.refresh()
    }
}

/// The UIKit side of `PreviewView`. Only the preview is rotated to the interface's
/// orientation; the frames the tracker gets stay as the sensor delivers them.
final class PreviewUIView: UIView {
    private let previewLayer: AVCaptureVideoPreviewLayer
    private let overlay: OverlayRenderer?

    init(session: AVCaptureSession, overlay: OverlayRenderer?, gravity: AVLayerVideoGravity) {
        previewLayer = AVCaptureVideoPreviewLayer(session: session)
        self.overlay = overlay
        super.init(frame: .zero)
        backgroundColor = .black
        previewLayer.videoGravity = gravity
        layer.addSublayer(previewLayer)
        if let overlay {
            layer.addSublayer(overlay.layer)
        }
    }

    required init?(coder: NSCoder) {
        return nil
    }

    override func layoutSubviews() {
        super.layoutSubviews()
        CATransaction.begin()
        CATransaction.setDisableActions(true)
        previewLayer.frame = bounds
        CATransaction.commit()
        refresh()
    }

    override func didMoveToWindow() {
        super.didMoveToWindow()
        refresh()
    }

    /// Sets the preview's rotation and lays the overlay over it again.
    func refresh() {
        updateOrientation()
        overlay?.attach(to: previewLayer, scale: max(traitCollection.displayScale, 1))
    }

    private func updateOrientation() {
        guard let connection = previewLayer.connection,
              let orientation = window?.windowScene?.interfaceOrientation
        else {
            return
        }
        if #available(iOS 17.0, *) {
            let angle = Self.rotationAngle(for: orientation)
            if connection.isVideoRotationAngleSupported(angle) {
                connection.videoRotationAngle = angle
            }
        } else if connection.isVideoOrientationSupported, let videoOrientation = Self.videoOrientation(for: orientation) {
            connection.videoOrientation = videoOrientation
        }
    }

    /// The preview's rotation (iOS 17) for an interface orientation: the sensor is landscape,
    /// home button (or its place) on the right.
    private static func rotationAngle(for orientation: UIInterfaceOrientation) -> CGFloat {
        switch orientation {
        case .landscapeRight: return 0
        case .landscapeLeft: return 180
        case .portraitUpsideDown: return 270
        default: return 90
        }
    }

    /// The preview's orientation (iOS 16) for an interface orientation.
    private static func videoOrientation(for orientation: UIInterfaceOrientation) -> AVCaptureVideoOrientation? {
        switch orientation {
        case .portrait: return .portrait
        case .portraitUpsideDown: return .portraitUpsideDown
        case .landscapeLeft: return .landscapeLeft
        case .landscapeRight: return .landscapeRight
        default: return nil
        }
    }
}
