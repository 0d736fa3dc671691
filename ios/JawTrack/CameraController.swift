// Adapts AVCaptureSession and AVCaptureDevice to JawTrackKit's CameraControl: applies the
// CapturePlan as given (the format CameraPlanner picks, pixel layout, frame duration, zoom,
// focus, automatic exposure and white balance, locked when the controller asks, the exposure
// cap, HDR and stabilisation off, the intrinsic matrix per frame). Every session call runs on its own serial
// queue: they block.
import AVFoundation
import JawTrackCore
import JawTrackKit

final class CameraController: CameraControl {
    let session = AVCaptureSession()
    private let queue = DispatchQueue(label: "org.jawtrack.session")
    private let output = AVCaptureVideoDataOutput()
    // Touched on `queue` only.
    private var input: AVCaptureDeviceInput?
    private var frames: PixelBufferFrames?

    func deliverFrames(to handler: @escaping (CameraFrame) -> Void, on frameQueue: DispatchQueue) {
        let frames = PixelBufferFrames(handler: handler)
        queue.async { [self] in
            self.frames = frames
            output.setSampleBufferDelegate(frames, queue: frameQueue)
        }
    }

    typealias Configured = Result<(CaptureConfiguration, VideoSinkFactory?), Error>

    func configure(_ plan: CapturePlan, settings: AppSettings, completion: @escaping (Configured) -> Void) {
        queue.async { [self] in completion(Result { try apply(plan, camera: settings.camera, resolution: settings.resolution) }) }
    }

    func start() {
        queue.async { [self] in
            if !session.isRunning { session.startRunning() }
        }
    }

    func lockExposureAndWhiteBalance(onProblem: @escaping (String) -> Void) {
        queue.async { [self] in
            guard session.isRunning, let device = input?.device else { return }
            do { try Self.lockExposureAndWhiteBalance(of: device) } catch { onProblem(PlatformText.exposureNotLocked(error)) }
        }
    }

    func limitExposure(to seconds: Double?) {
        queue.async { [self] in
            // Once locked, the exposure stays as it was (the cap applies to automatic exposure only).
            guard let device = input?.device, device.exposureMode == .continuousAutoExposure,
                  (try? device.lockForConfiguration()) != nil
            else { return }
            Self.applyExposureCap(seconds, to: device)
            device.unlockForConfiguration()
        }
    }

    func stop() {
        queue.async { [self] in session.stopRunning() }
    }

    /// Within the active format's range (outside it AVFoundation raises an exception); nil or
    /// `.invalid` gives automatic exposure its default limit back. Call with the device locked.
    private static func applyExposureCap(_ seconds: Double?, to device: AVCaptureDevice) {
        guard let seconds, seconds > 0 else {
            device.activeMaxExposureDuration = .invalid
            return
        }
        let format = device.activeFormat
        let wanted = CMTime(seconds: seconds, preferredTimescale: 1_000_000)
        device.activeMaxExposureDuration = CMTimeMaximum(
            format.minExposureDuration, CMTimeMinimum(wanted, format.maxExposureDuration)
        )
    }

    private func apply(
        _ plan: CapturePlan, camera: JawTrackCore.Camera, resolution: Resolution
    ) throws -> (CaptureConfiguration, VideoSinkFactory?) {
        let type: AVCaptureDevice.DeviceType = camera == .backTele ? .builtInTelephotoCamera : .builtInWideAngleCamera
        guard let device = AVCaptureDevice.default(type, for: .video, position: camera == .front ? .front : .back) else {
            throw CameraPlanner.missingCamera(camera)
        }
        let formats = device.formats.map(Self.info)
        let index = try CameraPlanner.chooseFormat(formats, resolution: resolution, fps: plan.fps)
        try configureSession(device, format: device.formats[index], plan: plan, camera: camera)
        // After the commit: the recommendation depends on the connection as configured.
        let codecs = output.availableVideoCodecTypesForAssetWriter(writingTo: .mov).map(\.rawValue)
        let recommended = CameraPlanner.videoCodec(among: codecs).flatMap {
            output.recommendedVideoSettings(forVideoCodecType: AVVideoCodecType(rawValue: $0), assetWriterOutputFileType: .mov)
        }
        let makeVideo = recommended.map { settings -> VideoSinkFactory in { url in try VideoWriter(url: url, settings: settings) } }
        return (CaptureConfiguration(format: formats[index], plan: plan, model: Self.model, camera: camera), makeVideo)
    }

    private func configureSession(
        _ device: AVCaptureDevice, format: AVCaptureDevice.Format, plan: CapturePlan, camera: JawTrackCore.Camera
    ) throws {
        session.beginConfiguration()
        defer { session.commitConfiguration() }
        if let input { session.removeInput(input) }
        let newInput = try AVCaptureDeviceInput(device: device)
        guard session.canAddInput(newInput) else { throw PlatformText.cameraBusy(camera) }
        session.addInput(newInput)
        input = newInput
        if !session.outputs.contains(output) {
            guard session.canAddOutput(output) else { throw PlatformText.framesUnavailable }
            session.addOutput(output)
        }
        let pixelFormat = plan.layout.pixelFormat
        guard output.availableVideoPixelFormatTypes.contains(pixelFormat) else { throw PlatformText.pixelFormatUnavailable(plan.layout) }
        output.videoSettings = [kCVPixelBufferPixelFormatTypeKey as String: pixelFormat]
        output.alwaysDiscardsLateVideoFrames = plan.discardLateFrames

        try device.lockForConfiguration()
        defer { device.unlockForConfiguration() }
        device.activeFormat = format
        let frameDuration = CMTime(value: 1, timescale: CMTimeScale(clamping: plan.fps))
        device.activeVideoMinFrameDuration = frameDuration
        device.activeVideoMaxFrameDuration = frameDuration
        device.videoZoomFactor = CGFloat(plan.zoomFactor)
        switch plan.focus {
        case .continuousAuto where device.isFocusModeSupported(.continuousAutoFocus): device.focusMode = .continuousAutoFocus
        case .continuousAuto: break
        case .locked(let lens) where device.isLockingFocusWithCustomLensPositionSupported:
            device.setFocusModeLocked(lensPosition: lens, completionHandler: nil)
        case .locked: throw PlatformText.noManualFocus(camera)
        }
        if device.isExposureModeSupported(.continuousAutoExposure) { device.exposureMode = .continuousAutoExposure }
        // After the format: setting the format resets the cap.
        Self.applyExposureCap(plan.maxExposure, to: device)
        if device.isWhiteBalanceModeSupported(.continuousAutoWhiteBalance) { device.whiteBalanceMode = .continuousAutoWhiteBalance }
        // Automatic HDR off first: setting the flag itself while automatic raises an exception.
        device.automaticallyAdjustsVideoHDREnabled = plan.videoHDR
        if device.activeFormat.isVideoHDRSupported { device.isVideoHDREnabled = plan.videoHDR }
        guard let connection = output.connection(with: .video) else { return }
        if connection.isCameraIntrinsicMatrixDeliverySupported {
            connection.isCameraIntrinsicMatrixDeliveryEnabled = plan.intrinsicMatrixDelivery
        }
        if connection.isVideoStabilizationSupported, !plan.stabilization { connection.preferredVideoStabilizationMode = .off }
    }

    private static func lockExposureAndWhiteBalance(of device: AVCaptureDevice) throws {
        guard device.isExposureModeSupported(.locked) else { throw PlatformText.exposureLockUnsupported }
        try device.lockForConfiguration()
        device.exposureMode = .locked
        if device.isWhiteBalanceModeSupported(.locked) { device.whiteBalanceMode = .locked }
        device.unlockForConfiguration()
    }

    private static func info(_ format: AVCaptureDevice.Format) -> CameraFormatInfo {
        let size = CMVideoFormatDescriptionGetDimensions(format.formatDescription)
        return CameraFormatInfo(
            width: Int(size.width),
            height: Int(size.height),
            frameRates: format.videoSupportedFrameRateRanges.map { $0.minFrameRate...$0.maxFrameRate },
            fullRange420: CMFormatDescriptionGetMediaSubType(format.formatDescription) == PixelLayout.luma.pixelFormat,
            fieldOfViewDegrees: format.videoFieldOfView,
            maxISO: format.maxISO
        )
    }

    /// The hardware model, e.g. "iPhone15,2".
    private static var model: String {
        var info = utsname()
        _ = uname(&info)
        return withUnsafeBytes(of: &info.machine) { raw in String(decoding: raw.prefix { $0 != 0 }, as: UTF8.self) }
    }
}
