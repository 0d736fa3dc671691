// Adapts AVCaptureVideoPreviewLayer to SwiftUI for JawTrackKit's ScreenState: the camera preview
// with the overlay's layers above it. Only the preview is turned to the interface's orientation;
// the frames the tracker gets stay as the sensor delivers them.
import AVFoundation
import JawTrackCore
import SwiftUI
import UIKit

@MainActor
struct PreviewView: UIViewRepresentable {
    let session: AVCaptureSession
    var overlay: JawTrackCore.Overlay?
    /// Changes when the camera is configured anew: the preview's connection is set again.
    var configurationID = 0
    var gravity: AVLayerVideoGravity = .resizeAspect

    func makeUIView(context: Context) -> PreviewUIView { PreviewUIView(session: session, gravity: gravity) }

    func updateUIView(_ view: PreviewUIView, context: Context) {
        if view.configurationID != configurationID {
            view.configurationID = configurationID
            view.refresh()
        }
        view.renderer.render(overlay)
    }
}

final class PreviewUIView: UIView {
    let previewLayer: AVCaptureVideoPreviewLayer
    let renderer: OverlayRenderer
    var configurationID = 0

    init(session: AVCaptureSession, gravity: AVLayerVideoGravity) {
        let preview = AVCaptureVideoPreviewLayer(session: session)
        previewLayer = preview
        renderer = OverlayRenderer(previewLayer: preview)
        super.init(frame: .zero)
        backgroundColor = .black
        preview.videoGravity = gravity
        layer.addSublayer(preview)
        layer.addSublayer(renderer.layer)
    }

    required init?(coder: NSCoder) { return nil }

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

    /// Turns the preview to the interface (UIInterfaceOrientation and AVCaptureVideoOrientation
    /// share their raw values) and lays the overlay over it again.
    func refresh() {
        if let orientation = window?.windowScene?.interfaceOrientation, orientation != .unknown,
           let videoOrientation = AVCaptureVideoOrientation(rawValue: orientation.rawValue),
           let connection = previewLayer.connection, connection.isVideoOrientationSupported {
            connection.videoOrientation = videoOrientation
        }
        renderer.redraw(scale: traitCollection.displayScale)
    }
}
