// Adapts Core Animation to JawTrackKit's OverlayGeometry: one shape layer per stroke (maxilla
// outlines cyan, mandible outlines yellow, x/y/z axes red/green/blue) and text layers for the
// tag ids, placed through the preview layer's own conversion from capture-device points.
import AVFoundation
import JawTrackCore
import JawTrackKit
import UIKit

@MainActor
final class OverlayRenderer {
    /// The overlay's root layer, over the preview layer with the same frame.
    let layer = CALayer()
    private let previewLayer: AVCaptureVideoPreviewLayer
    private let strokes: [CAShapeLayer]
    private var labels: [CATextLayer] = []
    private var last: JawTrackCore.Overlay?
    private var scale: CGFloat = 2

    init(previewLayer: AVCaptureVideoPreviewLayer) {
        self.previewLayer = previewLayer
        let colors: [UIColor] = [.systemCyan, .systemYellow, .systemRed, .systemGreen, .systemBlue]
        strokes = zip(colors, OverlayGeometry.strokeWidths).map { color, width in
            let shape = CAShapeLayer()
            shape.strokeColor = color.cgColor
            shape.fillColor = nil
            shape.lineWidth = CGFloat(width)
            shape.lineJoin = .round
            shape.lineCap = .round
            return shape
        }
        strokes.forEach { layer.addSublayer($0) }
    }

    /// After layout or rotation: the last overlay again, where the preview now is.
    func redraw(scale: CGFloat) {
        self.scale = scale
        render(last)
    }

    /// Shows `overlay` (nil: nothing).
    func render(_ overlay: JawTrackCore.Overlay?) {
        last = overlay
        let preview = previewLayer
        let geometry = OverlayGeometry(overlay) { point in
            let converted = preview.layerPointConverted(fromCaptureDevicePoint: CGPoint(x: point.x, y: point.y))
            return ViewPoint(x: Double(converted.x), y: Double(converted.y))
        }
        CATransaction.begin()
        CATransaction.setDisableActions(true)
        defer { CATransaction.commit() }
        layer.frame = preview.frame
        for (shape, lines) in zip(strokes, geometry.strokes) {
            let path = CGMutablePath()
            for line in lines {
                path.addLines(between: line.map { CGPoint(x: $0.x, y: $0.y) })
            }
            shape.path = path
        }
        while labels.count < geometry.labels.count {
            let text = CATextLayer()
            text.fontSize = 13
            text.alignmentMode = .center
            text.foregroundColor = UIColor.white.cgColor
            text.backgroundColor = UIColor.black.withAlphaComponent(0.55).cgColor
            text.cornerRadius = 4
            layer.addSublayer(text)
            labels.append(text)
        }
        for (index, text) in labels.enumerated() {
            text.isHidden = index >= geometry.labels.count
            guard !text.isHidden else { continue }
            let label = geometry.labels[index]
            text.string = label.text
            text.contentsScale = scale
            text.frame = CGRect(x: label.origin.x, y: label.origin.y, width: label.width, height: label.height)
        }
    }
}
