import AVFoundation
import JawTrackCore
import UIKit

/// Draws the tracker's overlay above the preview with Core Animation: shape layers whose paths
/// are replaced per result and composited by the GPU, so the camera frame is never redrawn.
/// Tag outlines per jaw, each tag's id, and each jaw's axes (x red, y green, z blue). The
/// geometry comes from the library in capture-device coordinates and goes through the preview
/// layer's own conversion, which accounts for its gravity, rotation and mirroring.
@MainActor
final class OverlayRenderer {
    /// The overlay's root layer, placed over the preview layer with the same frame.
    let layer = CALayer()

    private let outlines: [String: CAShapeLayer]
    private let axes: [CAShapeLayer]
    private var labels: [CATextLayer] = []
    private weak var previewLayer: AVCaptureVideoPreviewLayer?
    private var last: JawTrackCore.Overlay?
    private var scale: CGFloat = 2

    init() {
        outlines = [
            "maxilla": makeShapeLayer(color: UIColor.systemCyan, lineWidth: 2),
            "mandible": makeShapeLayer(color: UIColor.systemYellow, lineWidth: 2),
        ]
        axes = [UIColor.systemRed, UIColor.systemGreen, UIColor.systemBlue].map {
            makeShapeLayer(color: $0, lineWidth: 3)
        }
        for shape in outlines.values {
            layer.addSublayer(shape)
        }
        for shape in axes {
            layer.addSublayer(shape)
        }
    }

    /// Follows `previewLayer` (after layout or rotation) and redraws the last overlay there.
    func attach(to previewLayer: AVCaptureVideoPreviewLayer, scale: CGFloat) {
        self.previewLayer = previewLayer
        self.scale = scale
        CATransaction.begin()
        CATransaction.setDisableActions(true)
        layer.frame = previewLayer.frame
        CATransaction.commit()
        render(last)
    }

    /// Shows `overlay` (nil: nothing).
    func render(_ overlay: JawTrackCore.Overlay?) {
        last = overlay
        guard let previewLayer else {
            return
        }
        CATransaction.begin()
        CATransaction.setDisableActions(true)
        defer { CATransaction.commit() }

        var outlinePaths: [String: CGMutablePath] = [:]
        var labelCount = 0
        for tag in overlay?.tags ?? [] {
            let corners = (0..<4).compactMap { point(tag.corners, at: $0, in: previewLayer) }
            guard corners.count == 4 else {
                continue
            }
            let path = outlinePaths[tag.body] ?? CGMutablePath()
            path.addLines(between: corners)
            path.closeSubpath()
            outlinePaths[tag.body] = path
            if let center = point(tag.center, at: 0, in: previewLayer) {
                show(label(labelCount), text: String(tag.id), at: center)
                labelCount += 1
            }
        }
        for (body, shape) in outlines {
            shape.path = outlinePaths[body]
        }
        for unused in labels.dropFirst(labelCount) {
            unused.isHidden = true
        }

        let axisPaths = [CGMutablePath(), CGMutablePath(), CGMutablePath()]
        for axis in overlay?.axes ?? [] {
            guard let origin = point(axis.origin, at: 0, in: previewLayer) else {
                continue
            }
            for index in 0..<3 {
                if let end = point(axis.ends, at: index, in: previewLayer) {
                    axisPaths[index].move(to: origin)
                    axisPaths[index].addLine(to: end)
                }
            }
        }
        for (shape, path) in zip(axes, axisPaths) {
            shape.path = path
        }
    }

    /// Point `index` of an x, y list in capture-device coordinates, in the preview layer.
    private func point(_ xy: [Double], at index: Int, in previewLayer: AVCaptureVideoPreviewLayer) -> CGPoint? {
        let i = 2 * index
        guard xy.count >= i + 2, xy[i].isFinite, xy[i + 1].isFinite else {
            return nil
        }
        return previewLayer.layerPointConverted(fromCaptureDevicePoint: CGPoint(x: xy[i], y: xy[i + 1]))
    }

    /// The `index`-th id label, made when first needed and reused after.
    private func label(_ index: Int) -> CATextLayer {
        if index < labels.count {
            return labels[index]
        }
        let text = CATextLayer()
        text.fontSize = 13
        text.alignmentMode = .center
        text.foregroundColor = UIColor.white.cgColor
        text.backgroundColor = UIColor.black.withAlphaComponent(0.55).cgColor
        text.cornerRadius = 4
        layer.addSublayer(text)
        labels.append(text)
        return text
    }

    private func show(_ label: CATextLayer, text: String, at center: CGPoint) {
        label.string = text
        label.contentsScale = scale
        label.frame = CGRect(x: center.x - 16, y: center.y - 9, width: 32, height: 18)
        label.isHidden = false
    }
}

/// A stroke-only shape layer.
private func makeShapeLayer(color: UIColor, lineWidth: CGFloat) -> CAShapeLayer {
    let shape = CAShapeLayer()
    shape.strokeColor = color.cgColor
    shape.fillColor = nil
    shape.lineWidth = lineWidth
    shape.lineJoin = .round
    shape.lineCap = .round
    return shape
}
