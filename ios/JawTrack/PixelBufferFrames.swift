// Adapts AVCaptureVideoDataOutput's CMSampleBuffers to JawTrackKit's CameraFrame: the pixels in
// place while the CVPixelBuffer is locked (plane 0 of 420f as luma, or BGRA), the presentation
// time, the EXIF exposure time and ISO, the intrinsic matrix attachment, the lens position and
// focus activity as last observed (CameraController's LensReadings) and the sample buffer itself.
import AVFoundation
import ImageIO
import JawTrackKit

final class PixelBufferFrames: NSObject, AVCaptureVideoDataOutputSampleBufferDelegate {
    private let handler: (CameraFrame) -> Void
    private let lens: LensReadings

    init(handler: @escaping (CameraFrame) -> Void, lens: LensReadings) {
        self.handler = handler
        self.lens = lens
    }

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
        let lensNow = lens.current
        handler(CameraFrame(
            buffer: FrameBuffer(
                base: UnsafeRawPointer(base), byteCount: stride * height, width: width, height: height,
                bytesPerRow: stride, layout: layout
            ),
            time: CMSampleBufferGetPresentationTimeStamp(sampleBuffer).seconds,
            exposure: exif?[kCGImagePropertyExifExposureTime as String] as? Double,
            iso: (exif?[kCGImagePropertyExifISOSpeedRatings as String] as? [NSNumber])?.first?.doubleValue,
            cameraMatrix: CameraPlanner.cameraMatrix(fromAttachment: CMGetAttachment(
                sampleBuffer, key: kCMSampleBufferAttachmentKey_CameraIntrinsicMatrix, attachmentModeOut: nil
            ) as? Data),
            lensPosition: lensNow.position,
            adjustingFocus: lensNow.adjusting,
            native: sampleBuffer
        ))
    }
}
