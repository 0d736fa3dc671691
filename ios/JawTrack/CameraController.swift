import AVFoundation
import Foundation
import JawTrackCore

/// What the frame pipeline needs to know about the camera as configured.
struct CaptureConfiguration {
    /// The active format's size: the dimensions the delivered intrinsic matrix refers to.
    let referenceWidth: UInt32
    let referenceHeight: UInt32
    /// A pinhole matrix from the format's field of view (same layout as the delivered one), for
    /// frames that arrive without the intrinsic-matrix attachment.
    let estimatedMatrix: [Float]
    /// The phone model and camera, for the recording header (e.g. "iPhone15,2 back wide").
    let deviceDescription: String
    /// AVAssetWriter settings recommended for this format (HEVC when offered, else H.264).
    let videoSettings: [String: Any]?
}

/// Owns the capture session and sets it up from the settings. Every session call runs on the
/// controller's own serial queue, because they block; frames go to the delegate on its queue.
final class CameraController {
    let session = AVCaptureSession()

    private let queue = DispatchQueue(label: "org.jawtrack.session")
    private let output = AVCaptureVideoDataOutput()
    // Touched on `queue` only.
    private var input: AVCaptureDeviceInput?
    private var generation = 0

    /// Reconfigures the session for `settings` (camera, format, frame rate, focus, pixel format,
    /// intrinsics delivery) and sends frames to `delegate` on `delegateQueue`.
    func configure(
        _ settings: AppSettings,
        delegate: AVCaptureVideoDataOutputSampleBufferDelegate,
        delegateQueue: DispatchQueue,
        completion: @escaping @Sendable (Result<CaptureConfiguration, Error>) -> Void
    ) {
        queue.async { [self] in
            do {
                completion(.success(try reconfigure(settings, delegate: delegate, delegateQueue: delegateQueue)))
            } catch {
                completion(.failure(error))
            }
        }
    }

    /// Starts the session; with `lockingExposure`, locks the exposure once auto-exposure has had
    /// a second to settle.
    func start(lockingExposure: Bool, onProblem: @escaping @Sendable (String) -> Void) {
        queue.async { [self] in
            if !session.isRunning {
                session.startRunning()
            }
            guard lockingExposure else {
                return
            }
            let expected = generation
            queue.asyncAfter(deadline: .now() + 1) { [self] in
                guard generation == expected, session.isRunning, let device = input?.device else {
                    return
                }
                guard device.isExposureModeSupported(.locked) else {
                    onProblem("This camera cannot lock its exposure.")
                    return
                }
                do {
                    try device.lockForConfiguration()
                    device.exposureMode = .locked
                    device.unlockForConfiguration()
                } catch {
                    onProblem("The exposure could not be locked: \(error.localizedDescription)")
                }
            }
        }
    }

    /// Stops the session (settings screen, background).
    func stop() {
        queue.async { [self] in
            if session.isRunning {
                session.stopRunning()
            }
        }
    }

    private func reconfigure(
        _ settings: AppSettings,
        delegate: AVCaptureVideoDataOutputSampleBufferDelegate,
        delegateQueue: DispatchQueue
    ) throws -> CaptureConfiguration {
        generation += 1
        let device = try Self.device(for: settings.camera)
        let format = try Self.format(of: device, resolution: settings.resolution, fps: settings.fps)
        let pixelFormat = settings.bgra ? kCVPixelFormatType_32BGRA : kCVPixelFormatType_420YpCbCr8BiPlanarFullRange

        session.beginConfiguration()
        do {
            try attach(device, format: format, pixelFormat: pixelFormat, settings: settings, delegate: delegate, delegateQueue: delegateQueue)
        } catch {
            session.commitConfiguration()
            throw error
        }
        session.commitConfiguration()

        let size = CMVideoFormatDescriptionGetDimensions(format.formatDescription)
        let width = UInt32(clamping: size.width)
        let height = UInt32(clamping: size.height)
        let codecs = output.availableVideoCodecTypesForAssetWriter(writingTo: .mov)
        let codec: AVVideoCodecType = codecs.contains(.hevc) ? .hevc : .h264
        return CaptureConfiguration(
            referenceWidth: width,
            referenceHeight: height,
            estimatedMatrix: Self.matrix(width: width, height: height, fieldOfViewDegrees: format.videoFieldOfView),
            deviceDescription: "\(Self.modelIdentifier()) \(Self.title(of: settings.camera))",
            videoSettings: output.recommendedVideoSettings(forVideoCodecType: codec, assetWriterOutputFileType: .mov)
        )
    }

    /// The session part of `reconfigure`, between begin and commit.
    private func attach(
        _ device: AVCaptureDevice,
        format: AVCaptureDevice.Format,
        pixelFormat: OSType,
        settings: AppSettings,
        delegate: AVCaptureVideoDataOutputSampleBufferDelegate,
        delegateQueue: DispatchQueue
    ) throws {
        if let input {
            session.removeInput(input)
            self.input = nil
        }
        let newInput = try AVCaptureDeviceInput(device: device)
        guard session.canAddInput(newInput) else {
            throw AppError(message: "The \(Self.title(of: settings.camera)) camera cannot be used now.")
        }
        session.addInput(newInput)
        input = newInput
        if !session.outputs.contains(where: { $0 === output }) {
            guard session.canAddOutput(output) else {
                throw AppError(message: "The camera's frames cannot be read now.")
            }
            session.addOutput(output)
        }
        guard output.availableVideoPixelFormatTypes.contains(pixelFormat) else {
            throw AppError(message: "This camera does not deliver \(settings.bgra ? "BGRA" : "420f") frames.")
        }
        output.videoSettings = [kCVPixelBufferPixelFormatTypeKey as String: pixelFormat]
        output.alwaysDiscardsLateVideoFrames = true
        output.setSampleBufferDelegate(delegate, queue: delegateQueue)
        try Self.apply(settings, format: format, to: device)
        if let connection = output.connection(with: .video) {
            // Frames stay as the sensor delivers them (no rotation, no stabilisation warp), so
            // the intrinsics hold for every pixel.
            if connection.isCameraIntrinsicMatrixDeliverySupported {
                connection.isCameraIntrinsicMatrixDeliveryEnabled = true
            }
            if connection.isVideoStabilizationSupported {
                connection.preferredVideoStabilizationMode = .off
            }
        }
    }

    private static func apply(_ settings: AppSettings, format: AVCaptureDevice.Format, to device: AVCaptureDevice) throws {
        try device.lockForConfiguration()
        defer { device.unlockForConfiguration() }
        device.activeFormat = format
        let frameDuration = CMTime(value: 1, timescale: CMTimeScale(clamping: settings.fps))
        device.activeVideoMinFrameDuration = frameDuration
        device.activeVideoMaxFrameDuration = frameDuration
        device.videoZoomFactor = 1
        switch settings.focus {
        case .auto:
            if device.isFocusModeSupported(.continuousAutoFocus) {
                device.focusMode = .continuousAutoFocus
            }
        case .manual:
            guard device.isLockingFocusWithCustomLensPositionSupported else {
                throw AppError(message: "The \(title(of: settings.camera)) camera has no manual focus; choose auto.")
            }
            device.setFocusModeLocked(lensPosition: settings.lensPosition, completionHandler: nil)
        }
        if device.isExposureModeSupported(.continuousAutoExposure) {
            device.exposureMode = .continuousAutoExposure
        }
    }

    private static func device(for camera: JawTrackCore.Camera) throws -> AVCaptureDevice {
        let found: AVCaptureDevice?
        switch camera {
        case .backWide:
            found = AVCaptureDevice.default(.builtInWideAngleCamera, for: .video, position: .back)
        case .backTele:
            found = AVCaptureDevice.default(.builtInTelephotoCamera, for: .video, position: .back)
        case .front:
            found = AVCaptureDevice.default(.builtInWideAngleCamera, for: .video, position: .front)
        }
        guard let found else {
            throw AppError(message: "This iPhone has no \(title(of: camera)) camera.")
        }
        return found
    }

    /// A format of exactly the resolution that can run at `fps`, full-range 420 when offered.
    private static func format(of device: AVCaptureDevice, resolution: Resolution, fps: UInt32) throws -> AVCaptureDevice.Format {
        let (width, height) = dimensions(of: resolution)
        let rate = Float64(fps)
        let matching = device.formats.filter { format in
            let size = CMVideoFormatDescriptionGetDimensions(format.formatDescription)
            return size.width == width && size.height == height
                && format.videoSupportedFrameRateRanges.contains { $0.minFrameRate <= rate && rate <= $0.maxFrameRate }
        }
        let fullRange = matching.first {
            CMFormatDescriptionGetMediaSubType($0.formatDescription) == kCVPixelFormatType_420YpCbCr8BiPlanarFullRange
        }
        guard let chosen = fullRange ?? matching.first else {
            throw AppError(message: "This camera cannot film \(width)×\(height) at \(fps) fps; choose another resolution or frame rate.")
        }
        return chosen
    }

    private static func dimensions(of resolution: Resolution) -> (Int32, Int32) {
        switch resolution {
        case .hd720: return (1280, 720)
        case .hd1080: return (1920, 1080)
        case .uhd4k: return (3840, 2160)
        }
    }

    /// A column-major pinhole matrix (as AVFoundation's) from the horizontal field of view.
    private static func matrix(width: UInt32, height: UInt32, fieldOfViewDegrees: Float) -> [Float] {
        let halfAngle = Double(fieldOfViewDegrees) * Double.pi / 360
        let focal = Float(Double(width) / 2 / tan(halfAngle))
        return [focal, 0, 0, 0, focal, 0, Float(width) / 2, Float(height) / 2, 1]
    }

    static func title(of camera: JawTrackCore.Camera) -> String {
        switch camera {
        case .backWide: return "back wide"
        case .backTele: return "back telephoto"
        case .front: return "front"
        }
    }

    /// The hardware model, e.g. "iPhone15,2".
    private static func modelIdentifier() -> String {
        var info = utsname()
        _ = uname(&info)
        return withUnsafeBytes(of: &info.machine) { raw in
            String(decoding: raw.prefix { $0 != 0 }, as: UTF8.self)
        }
    }
}
