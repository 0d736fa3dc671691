// Adapts AVCaptureSession and AVCaptureDevice to JawTrackKit's CameraControl: describes the
// physical camera (model, nearest focus, formats with field of view, frame rates and native
// crops), applies the CaptureSetup as given (the format at its index, pixel layout, frame
// duration, zoom, focus, automatic exposure and white balance, locked when the controller asks,
// the exposure cap, HDR and stabilisation off, the intrinsic matrix per frame), locks the focus
// where it settled when the controller asks, and keeps the lens position and focus activity
// (key-value observed, in LensReadings) for the frames. Every session call runs on its own
// serial queue: they block.
import AVFoundation
import JawTrackCore
import JawTrackKit

final class CameraController: CameraControl {
    let session = AVCaptureSession()
    private let queue = DispatchQueue(label: "org.jawtrack.session")
    private let output = AVCaptureVideoDataOutput()
    /// The lens as last observed: written by key-value observation, read on the frame queue.
    private let lens = LensReadings()
    // Touched on `queue` only.
    private var input: AVCaptureDeviceInput?
    private var frames: PixelBufferFrames?
    /// The plan and camera as configured.
    private var plan: CapturePlan?
    private var camera: JawTrackCore.Camera?
    private var lensObservations: [NSKeyValueObservation] = []

    func deliverFrames(to handler: @escaping (CameraFrame) -> Void, on frameQueue: DispatchQueue) {
        let frames = PixelBufferFrames(handler: handler, lens: lens)
        queue.async { [self] in
            self.frames = frames
            output.setSampleBufferDelegate(frames, queue: frameQueue)
        }
    }

    func describe(_ camera: JawTrackCore.Camera, completion: @escaping (Result<CameraDevice, Error>) -> Void) {
        queue.async { completion(Result { try Self.description(of: Self.device(for: camera), camera: camera) }) }
    }

    func configure(_ setup: CaptureSetup, completion: @escaping (Result<VideoSinkFactory?, Error>) -> Void) {
        queue.async { [self] in completion(Result { try apply(setup) }) }
    }

    func start() {
        queue.async { [self] in
            // A focus locked in an earlier session is let go: the phone may be elsewhere now.
            if plan?.focus == .continuousAutoUntilLocked, let device = input?.device,
               (try? device.lockForConfiguration()) != nil {
                Self.focusOnTheCentre(device)
                device.unlockForConfiguration()
            }
            if !session.isRunning { session.startRunning() }
        }
    }

    func lockFocus(completion: @escaping (Result<Double, Error>) -> Void) {
        queue.async { [self] in
            guard session.isRunning, let device = input?.device, let camera else {
                completion(.failure(PlatformText.framesUnavailable))
                return
            }
            // Locking where the lens is (`currentLensPosition`) needs the locked mode, not
            // `isLockingFocusWithCustomLensPositionSupported` (that is for other positions).
            guard device.isFocusModeSupported(.locked) else {
                completion(.failure(PlatformText.focusLockUnsupported(camera)))
                return
            }
            do {
                try device.lockForConfiguration()
            } catch {
                completion(.failure(error))
                return
            }
            let queue = self.queue
            device.setFocusModeLocked(lensPosition: AVCaptureDevice.currentLensPosition) { _ in
                // The lens is locked now (it may have moved on since the call): where it is, it stays.
                queue.async { completion(.success(Double(device.lensPosition))) }
            }
            device.unlockForConfiguration()
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

    /// The physical camera: the wide-angle (or telephoto) module itself, never a virtual
    /// multi-camera that switches lenses with distance or zoom (the intrinsics, the focus and the
    /// capture plan belong to one lens).
    private static func device(for camera: JawTrackCore.Camera) throws -> AVCaptureDevice {
        let type: AVCaptureDevice.DeviceType = camera == .backTele ? .builtInTelephotoCamera : .builtInWideAngleCamera
        guard let device = AVCaptureDevice.default(type, for: .video, position: camera == .front ? .front : .back) else {
            throw CameraPlanner.missingCamera(camera)
        }
        return device
    }

    private static func description(of device: AVCaptureDevice, camera: JawTrackCore.Camera) -> CameraDevice {
        CameraDevice(
            model: model,
            camera: camera,
            minimumFocusMm: CameraDevice.focusDistance(reported: device.minimumFocusDistance),
            formats: device.formats.map(info)
        )
    }

    private func apply(_ setup: CaptureSetup) throws -> VideoSinkFactory? {
        let camera = setup.device.camera
        let device = try Self.device(for: camera)
        let index = setup.formatIndex
        guard device.formats.indices.contains(index), Self.info(device.formats[index]) == setup.format else {
            throw PlatformText.formatUnavailable
        }
        try configureSession(device, format: device.formats[index], plan: setup.plan, camera: camera)
        plan = setup.plan
        self.camera = camera
        // After the commit: the recommendation depends on the connection as configured.
        let codecs = output.availableVideoCodecTypesForAssetWriter(writingTo: .mov).map(\.rawValue)
        let recommended = CameraPlanner.videoCodec(among: codecs).flatMap {
            output.recommendedVideoSettings(forVideoCodecType: AVVideoCodecType(rawValue: $0), assetWriterOutputFileType: .mov)
        }
        return recommended.map { settings -> VideoSinkFactory in { url in try VideoWriter(url: url, settings: settings) } }
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
        observeLens(of: device)
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
        // After the format (setting it resets the zoom): 1, or the plan's native crop, never
        // beyond what the format allows (beyond it AVFoundation raises an exception).
        device.videoZoomFactor = min(max(CGFloat(plan.zoomFactor), 1), device.activeFormat.videoMaxZoomFactor)
        switch plan.focus {
        case .continuousAuto where device.isFocusModeSupported(.continuousAutoFocus): device.focusMode = .continuousAutoFocus
        case .continuousAuto: break
        case .locked(let position) where device.isLockingFocusWithCustomLensPositionSupported:
            device.setFocusModeLocked(lensPosition: position, completionHandler: nil)
        case .locked: throw PlatformText.noManualFocus(camera)
        case .continuousAutoUntilLocked: Self.focusOnTheCentre(device)
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

    /// Continuous autofocus on the centre of the frame, without smooth autofocus's slow glide:
    /// the capture plan's focus until the controller locks it. Call with the device locked.
    private static func focusOnTheCentre(_ device: AVCaptureDevice) {
        // The point first: it takes effect when the focus mode is set.
        if device.isFocusPointOfInterestSupported { device.focusPointOfInterest = CGPoint(x: 0.5, y: 0.5) }
        if device.isSmoothAutoFocusSupported { device.isSmoothAutoFocusEnabled = false }
        if device.isFocusModeSupported(.continuousAutoFocus) { device.focusMode = .continuousAutoFocus }
    }

    /// Keeps the device's lens position and whether it is adjusting its focus (both key-value
    /// observable; the notifications come on AVFoundation's threads) for the frames.
    private func observeLens(of device: AVCaptureDevice) {
        let lens = self.lens
        lensObservations = []
        lens.reset()
        lensObservations = [
            device.observe(\.lensPosition, options: [.initial, .new]) { _, change in
                if let position = change.newValue { lens.set(position: Double(position)) }
            },
            device.observe(\.isAdjustingFocus, options: [.initial, .new]) { _, change in
                if let adjusting = change.newValue { lens.set(adjusting: adjusting) }
            },
        ]
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
        var nativeZooms: [Double] = []
        if #available(iOS 16.0, *) {
            nativeZooms = format.secondaryNativeResolutionZoomFactors.map { Double($0) }
        }
        return CameraFormatInfo(
            width: Int(size.width),
            height: Int(size.height),
            frameRates: format.videoSupportedFrameRateRanges.map { $0.minFrameRate...$0.maxFrameRate },
            fullRange420: CMFormatDescriptionGetMediaSubType(format.formatDescription) == PixelLayout.luma.pixelFormat,
            fieldOfViewDegrees: format.videoFieldOfView,
            maxISO: format.maxISO,
            nativeZooms: nativeZooms
        )
    }

    /// The hardware model, e.g. "iPhone15,2".
    private static var model: String {
        var info = utsname()
        _ = uname(&info)
        return withUnsafeBytes(of: &info.machine) { raw in String(decoding: raw.prefix { $0 != 0 }, as: UTF8.self) }
    }
}

/// The lens as the device last reported it: written from key-value observation (on
/// AVFoundation's threads), read for each frame on the frame queue, so guarded by a lock.
final class LensReadings {
    private let lock = NSLock()
    private var position: Double?
    private var adjusting: Bool?

    func set(position: Double) {
        lock.lock()
        self.position = position
        lock.unlock()
    }

    func set(adjusting: Bool) {
        lock.lock()
        self.adjusting = adjusting
        lock.unlock()
    }

    /// A new device: nothing known yet.
    func reset() {
        lock.lock()
        position = nil
        adjusting = nil
        lock.unlock()
    }

    /// The lens position (0 near – 1 far) and whether focus is adjusting, as last reported.
    var current: (position: Double?, adjusting: Bool?) {
        lock.lock()
        defer { lock.unlock() }
        return (position, adjusting)
    }
}
