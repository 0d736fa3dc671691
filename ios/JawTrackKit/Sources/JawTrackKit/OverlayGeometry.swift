import Foundation
import JawTrackCore

/// A point in the view's coordinates (points, origin top-left).
public struct ViewPoint: Equatable {
    public var x: Double
    public var y: Double

    public init(x: Double, y: Double) {
        self.x = x
        self.y = y
    }
}

/// What the overlay draws, in view coordinates: closed tag outlines per jaw, id labels, and
/// the three axes of each jaw (x red, y green, z blue). The library gives the geometry in
/// capture-device coordinates ((0, 0) top-left, (1, 1) bottom-right of the sensor frame); the
/// app's only part is `convert`, the preview layer's `layerPointConverted(fromCaptureDevicePoint:)`,
/// which accounts for its gravity, rotation and mirroring.
public struct OverlayGeometry: Equatable {
    public struct Label: Equatable {
        public let text: String
        /// The label's box (centred on the tag).
        public let origin: ViewPoint
        public let width: Double
        public let height: Double

        public init(text: String, origin: ViewPoint, width: Double, height: Double) {
            self.text = text
            self.origin = origin
            self.width = width
            self.height = height
        }
    }

    /// Per body ("maxilla", "mandible"): each tag's four corners.
    public var outlines: [String: [[ViewPoint]]] = [:]
    public var labels: [Label] = []
    /// Index 0, 1, 2: the x, y, z axis segments (from, to) of every body.
    public var axes: [[(ViewPoint, ViewPoint)]] = [[], [], []]

    public static let labelWidth = 32.0
    public static let labelHeight = 18.0

    public init() {}

    public init(_ overlay: Overlay?, convert: (ViewPoint) -> ViewPoint) {
        guard let overlay else {
            return
        }
        for tag in overlay.tags {
            let corners = (0..<4).compactMap { Self.point(tag.corners, at: $0) }
            guard corners.count == 4, let center = Self.point(tag.center, at: 0) else {
                continue
            }
            outlines[tag.body, default: []].append(corners.map(convert))
            let c = convert(center)
            labels.append(Label(
                text: String(tag.id),
                origin: ViewPoint(x: c.x - Self.labelWidth / 2, y: c.y - Self.labelHeight / 2),
                width: Self.labelWidth,
                height: Self.labelHeight
            ))
        }
        for axis in overlay.axes {
            guard let origin = Self.point(axis.origin, at: 0) else {
                continue
            }
            let from = convert(origin)
            for index in 0..<3 {
                if let end = Self.point(axis.ends, at: index) {
                    axes[index].append((from, convert(end)))
                }
            }
        }
    }

    /// Point `index` of an x, y list, when present and finite.
    static func point(_ xy: [Double], at index: Int) -> ViewPoint? {
        let i = 2 * index
        guard xy.count >= i + 2, xy[i].isFinite, xy[i + 1].isFinite else {
            return nil
        }
        return ViewPoint(x: xy[i], y: xy[i + 1])
    }

    public static func == (a: OverlayGeometry, b: OverlayGeometry) -> Bool {
        a.outlines == b.outlines && a.labels == b.labels
            && a.axes.count == b.axes.count
            && zip(a.axes, b.axes).allSatisfy { x, y in
                x.count == y.count && zip(x, y).allSatisfy { $0.0 == $1.0 && $0.1 == $1.1 }
            }
    }
}

extension OverlayGeometry {
    /// The overlay's stroke layers, in the order of `strokes`: the maxilla's tag outlines, the
    /// mandible's, then the x, y and z axes. Their widths in points.
    public static let strokeWidths: [Double] = [2, 2, 3, 3, 3]

    /// The polylines each stroke layer draws, in `strokeWidths` order; an outline ends at its
    /// first corner again, so it is drawn closed.
    public var strokes: [[[ViewPoint]]] {
        let closedOutlines: [[[ViewPoint]]] = ["maxilla", "mandible"].map { body in
            (outlines[body] ?? []).map { corners in corners + Array(corners.prefix(1)) }
        }
        let axisLines: [[[ViewPoint]]] = axes.map { segments in segments.map { [$0.0, $0.1] } }
        return closedOutlines + axisLines
    }
}
