import CoreVideo
import Foundation
import JawTrackC

/// Why a camera frame could not be tracked.
public struct FramePathError: Error, LocalizedError {
    /// What went wrong, for the status bar.
    public let message: String

    public var errorDescription: String? { message }
}

/// The frame door of the library: hands a camera frame's pixels to `jt_track_luma` or
/// `jt_track_bgra` in place, so no frame is ever copied on its way to the detector (the uniffi
/// `Tracker.trackLuma` copies, which is why it is not used here). The full result is then read
/// with `Tracker.lastResult()`.
public enum FramePath {
    /// Tracks `pixelBuffer` (420f: its luma plane as is; BGRA: converted by the library) with
    /// the tracker reached by `handle`. Call it on the serial queue that owns the tracker.
    public static func track(
        _ pixelBuffer: CVPixelBuffer,
        handle: UInt64,
        intrinsics: Intrinsics,
        time: Double
    ) throws {
        let format = CVPixelBufferGetPixelFormatType(pixelBuffer)
        guard CVPixelBufferLockBaseAddress(pixelBuffer, .readOnly) == kCVReturnSuccess else {
            throw FramePathError(message: "the camera frame could not be locked for reading")
        }
        defer { CVPixelBufferUnlockBaseAddress(pixelBuffer, .readOnly) }

        var camera = JtIntrinsics(
            fx: intrinsics.fx,
            fy: intrinsics.fy,
            cx: intrinsics.cx,
            cy: intrinsics.cy,
            k1: intrinsics.k1,
            k2: intrinsics.k2
        )
        let status: JtStatus
        switch format {
        case kCVPixelFormatType_420YpCbCr8BiPlanarFullRange:
            guard let base = CVPixelBufferGetBaseAddressOfPlane(pixelBuffer, 0) else {
                throw FramePathError(message: "the camera frame has no luma plane")
            }
            let bytesPerRow = CVPixelBufferGetBytesPerRowOfPlane(pixelBuffer, 0)
            let width = CVPixelBufferGetWidthOfPlane(pixelBuffer, 0)
            let height = CVPixelBufferGetHeightOfPlane(pixelBuffer, 0)
            status = jt_track_luma(
                handle,
                base.assumingMemoryBound(to: UInt8.self),
                bytesPerRow * height,
                UInt32(clamping: width),
                UInt32(clamping: height),
                UInt32(clamping: bytesPerRow),
                &camera,
                time,
                nil
            )
        case kCVPixelFormatType_32BGRA:
            guard let base = CVPixelBufferGetBaseAddress(pixelBuffer) else {
                throw FramePathError(message: "the camera frame has no pixels")
            }
            let bytesPerRow = CVPixelBufferGetBytesPerRow(pixelBuffer)
            let width = CVPixelBufferGetWidth(pixelBuffer)
            let height = CVPixelBufferGetHeight(pixelBuffer)
            status = jt_track_bgra(
                handle,
                base.assumingMemoryBound(to: UInt8.self),
                bytesPerRow * height,
                UInt32(clamping: width),
                UInt32(clamping: height),
                UInt32(clamping: bytesPerRow),
                &camera,
                time,
                nil
            )
        default:
            throw FramePathError(message: "unsupported pixel format \(fourCharacterCode(format))")
        }
        guard status == JT_STATUS_OK else {
            throw FramePathError(message: lastError())
        }
    }

    /// The library's message for this thread's last failed call.
    private static func lastError() -> String {
        let capacity = 512
        var buffer = [CChar](repeating: 0, count: capacity)
        let length = jt_last_error(&buffer, capacity)
        let bytes = buffer.prefix { $0 != 0 }.map { UInt8(bitPattern: $0) }
        let message = String(decoding: bytes, as: UTF8.self)
        if message.isEmpty {
            return "tracking failed (no message, \(length) bytes)"
        }
        return message
    }

    /// A pixel format as its four letters, e.g. `420v`.
    private static func fourCharacterCode(_ code: OSType) -> String {
        let bytes = [24, 16, 8, 0].map { UInt8(truncatingIfNeeded: code >> $0) }
        return String(decoding: bytes, as: UTF8.self)
    }
}
