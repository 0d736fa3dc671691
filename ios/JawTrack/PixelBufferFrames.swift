// Adapts AVCaptureVideoDataOutput's CMSampleBuffers to JawTrackKit's CameraFrame: the pixels in
// place while the CVPixelBuffer is locked (plane 0 of 420f as luma, or BGRA), the presentation
// time, the EXIF exposure time, the intrinsic matrix attachment and the sample buffer itself.
import AVFoundation
import ImageIO
import JawTrackKit
import simd

final class PixelBufferFrames: NSObject, AVCaptureVideoDataOutputSampleBufferDelegate {
    private let handler: (CameraFrame) -> Void

    init(handler: @escaping (CameraFrame) -> Void) { self.handler = handler }

    func captureOutput(_ output: AVCaptureOutput, didOutput sampleBuffer: CMSampleBuffer, from connection: AVCaptureConnection) {
        guard let pixels = CMSampleBufferGetImageBuffer(sampleBuffer),
              let layout = PixelLayout(pixelFormat: CVPixelBufferGetPixelFormatType(pixels))
        else { return }
        CVPixelBufferLockBaseAddress(pixels, .readOnly)
        defer { CVPixelBufferUnlockBaseAddress(pixels, .readOnly) }
        let luma = layout == .luma
        guard let base = luma ? CVPixelBufferGetBaseAddressOfPlane(pixels, 0) : CVPixelBufferGetBaseAddress(pixels) else { return }
        let stride = luma ? CVPixelBufferGetBytesPerRowOfPlane(pixels, 0) : CVPixelBufferGetBytesPerRow(pixels)
        let width = luma ? CVPixelBufferGetWidthOfPlane(pixels, 0) : CVPixelBufferGetWidth(pixels)
        let height = luma ? CVPixelBufferGetHeightOfPlane(pixels, 0) : CVPixelBufferGetHeight(pixels)
        let exif = CMGetAttachment(sampleBuffer, key: kCGImagePropertyExifDictionary, attachmentModeOut: nil) as? [String: Any]
        handler(CameraFrame(
            buffer: FrameBuffer(
                base: UnsafeRawPointer(base), byteCount: stride * height, width: width, height: height,
                bytesPerRow: stride, layout: layout
            ),
            time: CMSampleBufferGetPresentationTimeStamp(sampleBuffer).seconds,
            exposure: exif?[kCGImagePropertyExifExposureTime as String] as? Double,
            cameraMatrix: Self.intrinsicMatrix(of: sampleBuffer),
            native: sampleBuffer
        ))
    }

    /// AVFoundation's intrinsic matrix for this frame: a `matrix_float3x3` in a CFData,
    /// column-major, as nine numbers.
    private static func intrinsicMatrix(of sampleBuffer: CMSampleBuffer) -> [Float]? {
        let attachment = CMGetAttachment(sampleBuffer, key: kCMSampleBufferAttachmentKey_CameraIntrinsicMatrix, attachmentModeOut: nil)
        guard let data = attachment as? Data, data.count >= MemoryLayout<matrix_float3x3>.size else { return nil }
        var matrix = matrix_float3x3()
        _ = withUnsafeMutableBytes(of: &matrix) { data.copyBytes(to: $0) }
        let (c0, c1, c2) = matrix.columns
        return [c0.x, c0.y, c0.z, c1.x, c1.y, c1.z, c2.x, c2.y, c2.z]
    }
}
