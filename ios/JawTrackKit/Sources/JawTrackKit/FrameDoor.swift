import Foundation
import JawTrackC
import JawTrackCore

/// How a frame's pixels are laid out.
public enum PixelLayout: Equatable {
    /// 8-bit luma rows: plane 0 of a full-range 420f frame, read as is.
    case luma
    /// 32-bit BGRA rows, converted to luma by the library.
    case bgra

    /// Bytes per pixel.
    public var bytesPerPixel: Int {
        switch self {
        case .luma: return 1
        case .bgra: return 4
        }
    }
}

/// A camera frame's pixels, borrowed: valid only while the frame source holds them (inside the
/// `CVPixelBuffer` lock in the app), so nothing keeps it beyond the call it is passed to.
public struct FrameBuffer {
    public let base: UnsafeRawPointer
    /// Bytes readable from `base`.
    public let byteCount: Int
    public let width: Int
    public let height: Int
    /// Bytes from one row's start to the next (rows may be padded).
    public let bytesPerRow: Int
    public let layout: PixelLayout

    public init(base: UnsafeRawPointer, byteCount: Int, width: Int, height: Int, bytesPerRow: Int, layout: PixelLayout) {
        self.base = base
        self.byteCount = byteCount
        self.width = width
        self.height = height
        self.bytesPerRow = bytesPerRow
        self.layout = layout
    }
}

/// One frame as a `FrameSource` delivers it.
public struct CameraFrame {
    public let buffer: FrameBuffer
    /// The frame's time (s): its presentation time stamp.
    public let time: Double
    /// How long the sensor exposed it (s), when the camera says.
    public let exposure: Double?
    /// The sensor's gain (ISO) for it, when the camera says.
    public let iso: Double?
    /// The camera's intrinsic matrix for this frame (nine numbers, column-major, in pixels of
    /// the active format), when delivered.
    public let cameraMatrix: [Float]?
    /// The lens position (0 near – 1 far) while the frame was taken, when the camera says:
    /// focusing moves the lens and scales the image, so it is recorded with the frame.
    public let lensPosition: Double?
    /// Whether the camera was adjusting its focus, when it says.
    public let adjustingFocus: Bool?
    /// The platform's own frame (a `CMSampleBuffer` in the app), handed untouched to the video
    /// writer; nil in tests.
    public let native: AnyObject?

    public init(
        buffer: FrameBuffer, time: Double, exposure: Double?, iso: Double? = nil, cameraMatrix: [Float]?,
        lensPosition: Double? = nil, adjustingFocus: Bool? = nil, native: AnyObject? = nil
    ) {
        self.buffer = buffer
        self.time = time
        self.exposure = exposure
        self.iso = iso
        self.cameraMatrix = cameraMatrix
        self.lensPosition = lensPosition
        self.adjustingFocus = adjustingFocus
        self.native = native
    }
}

/// Where frames come from (the camera in the app, fixture files in tests). The source calls
/// `handler` on the pipeline's queue, once per frame, with pixels valid during the call only.
public protocol FrameSource: AnyObject {
    func deliverFrames(to handler: @escaping (CameraFrame) -> Void, on queue: DispatchQueue)
}

/// The frame door of the library: hands a frame's pixels to `jt_track_luma` or `jt_track_bgra`
/// in place, so no frame is copied on its way to the detector (the uniffi `Tracker.trackLuma`
/// copies, which is why it is not used here). The full result is then `Tracker.lastResult()`.
public enum FrameDoor {
    /// Tracks `buffer` with the tracker reached by `handle`; `exposure` (s), when the camera
    /// said, is recorded with the frame. Throws the library's message.
    public static func track(
        _ buffer: FrameBuffer, handle: UInt64, intrinsics: Intrinsics, time: Double, exposure: Double?
    ) throws {
        var camera = JtIntrinsics(
            fx: intrinsics.fx, fy: intrinsics.fy, cx: intrinsics.cx, cy: intrinsics.cy,
            k1: intrinsics.k1, k2: intrinsics.k2
        )
        let pixels = buffer.base.assumingMemoryBound(to: UInt8.self)
        let width = UInt32(clamping: buffer.width)
        let height = UInt32(clamping: buffer.height)
        let stride = UInt32(clamping: buffer.bytesPerRow)
        // The library reads 0 as "not known".
        let exposureSeconds = exposure ?? 0
        let status: JtStatus
        switch buffer.layout {
        case .luma:
            status = jt_track_luma(handle, pixels, buffer.byteCount, width, height, stride, &camera, time, exposureSeconds, nil)
        case .bgra:
            status = jt_track_bgra(handle, pixels, buffer.byteCount, width, height, stride, &camera, time, exposureSeconds, nil)
        }
        guard status == JT_STATUS_OK else {
            throw AppError(message: lastError())
        }
    }

    /// The library's message for this thread's last failed call.
    static func lastError() -> String {
        let capacity = 512
        var buffer = [CChar](repeating: 0, count: capacity)
        let length = jt_last_error(&buffer, capacity)
        let bytes = buffer.prefix { $0 != 0 }.map { UInt8(bitPattern: $0) }
        let message = String(decoding: bytes, as: UTF8.self)
        return message.isEmpty ? "tracking failed (no message, \(length) bytes)" : message
    }

    /// A pixel format code as its four letters, e.g. `420v`.
    public static func fourCharacterCode(_ code: UInt32) -> String {
        let bytes = [24, 16, 8, 0].map { UInt8(truncatingIfNeeded: code >> $0) }
        return String(decoding: bytes, as: UTF8.self)
    }
}

extension PixelLayout {
    /// The CoreVideo pixel format of the layout: `420f` (kCVPixelFormatType_420YpCbCr8BiPlanarFullRange)
    /// or `BGRA` (kCVPixelFormatType_32BGRA).
    public var pixelFormat: UInt32 {
        switch self {
        case .luma: return 0x3432_3066
        case .bgra: return 0x4247_5241
        }
    }

    /// The layout of frames in `pixelFormat`; nil for any other format.
    public init?(pixelFormat: UInt32) {
        guard let layout = [PixelLayout.luma, .bgra].first(where: { $0.pixelFormat == pixelFormat }) else {
            return nil
        }
        self = layout
    }
}
