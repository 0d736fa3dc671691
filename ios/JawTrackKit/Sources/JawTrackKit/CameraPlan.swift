import Foundation
import JawTrackCore

/// One of a camera's formats, as the app's camera layer describes it (from
/// `AVCaptureDevice.Format`), so that choosing among them is decided here.
public struct CameraFormatInfo: Equatable {
    public let width: Int
    public let height: Int
    /// The frame rates it supports, as closed ranges (fps).
    public let frameRates: [ClosedRange<Double>]
    /// Whether its native pixel format is full-range 4:2:0 (`420f`), whose luma plane the
    /// detector reads as is.
    public let fullRange420: Bool
    /// Horizontal field of view (°).
    public let fieldOfViewDegrees: Float
    /// The highest sensor gain (ISO) the format reaches; 0 when not known.
    public let maxISO: Float

    public init(
        width: Int, height: Int, frameRates: [ClosedRange<Double>], fullRange420: Bool, fieldOfViewDegrees: Float,
        maxISO: Float = 0
    ) {
        self.width = width
        self.height = height
        self.frameRates = frameRates
        self.fullRange420 = fullRange420
        self.fieldOfViewDegrees = fieldOfViewDegrees
        self.maxISO = maxISO
    }
}

/// How the focus is to be set.
public enum FocusPlan: Equatable {
    case continuousAuto
    /// Locked at a lens position (0 near … 1 far).
    case locked(lensPosition: Float)
}

/// How the camera is to be set for measuring, from the settings. The camera layer applies it
/// and decides nothing: metrology needs frames as the sensor gives them (no stabilisation warp,
/// no HDR tone mapping that changes between frames), the intrinsic matrix per frame, and on
/// demand an exposure and white balance that stay put.
public struct CapturePlan: Equatable {
    public let layout: PixelLayout
    public let fps: UInt32
    public let focus: FocusPlan
    /// Lock exposure and white balance this many seconds after the session starts (time for
    /// auto-exposure to settle); nil: both stay automatic.
    public let lockExposureAfter: Double?
    /// The longest exposure automatic exposure may choose at first (s; nil: the camera's own
    /// limit). The pipeline lifts it while the room is too dark (`nextExposureCap`).
    public let maxExposure: Double?
    /// Video HDR and its automatic adjustment: always off (tone mapping varies frame to frame).
    public let videoHDR = false
    /// Video stabilisation: always off (it crops and warps, so the intrinsics would not hold).
    public let stabilization = false
    /// Ask for the intrinsic matrix with every frame.
    public let intrinsicMatrixDelivery = true
    /// Drop frames that arrive while one is being tracked: a late pose is worthless.
    public let discardLateFrames = true
    public let zoomFactor = 1.0
    /// Seconds a frame lasts at the chosen rate.
    public var frameDuration: Double { 1 / Double(fps) }

    public init(_ settings: AppSettings) {
        layout = settings.bgra ? .bgra : .luma
        fps = settings.fps
        switch settings.focus {
        case .auto: focus = .continuousAuto
        case .manual: focus = .locked(lensPosition: min(max(settings.lensPosition, 0), 1))
        }
        lockExposureAfter = settings.exposureLocked ? 1 : nil
        maxExposure = settings.maxExposureS > 0 ? settings.maxExposureS : nil
    }
}

/// What the frame pipeline knows of the camera as configured.
public struct CaptureConfiguration: Equatable {
    /// The active format's size: what the delivered intrinsic matrix refers to.
    public let referenceWidth: UInt32
    public let referenceHeight: UInt32
    /// A pinhole matrix from the format's field of view (same layout as the delivered one), for
    /// frames that arrive without one.
    public let estimatedMatrix: [Float]
    /// The phone model and camera, for the recording header (e.g. "iPhone15,2 back wide").
    public let deviceDescription: String
    /// Seconds between frames at the configured rate.
    public let frameDuration: Double
    /// The hardware model (e.g. "iPhone16,2") and the camera: what the readout table is keyed by.
    public let model: String
    public let camera: Camera
    /// The format's highest sensor gain (0: not known) and the exposure cap asked for (nil: none).
    public let maxISO: Double
    public let maxExposure: Double?

    public init(format: CameraFormatInfo, plan: CapturePlan, model: String, camera: Camera) {
        self.model = model
        self.camera = camera
        maxISO = Double(format.maxISO)
        maxExposure = plan.maxExposure
        referenceWidth = UInt32(clamping: format.width)
        referenceHeight = UInt32(clamping: format.height)
        estimatedMatrix = CameraPlanner.pinholeMatrix(
            width: referenceWidth, height: referenceHeight, fieldOfViewDegrees: format.fieldOfViewDegrees
        )
        deviceDescription = "\(model) \(CameraPlanner.title(of: camera))"
        frameDuration = plan.frameDuration
    }
}

/// The camera decisions that do not need the camera.
public enum CameraPlanner {
    /// The frame size of a resolution setting (landscape, as the sensor delivers).
    public static func dimensions(of resolution: Resolution) -> (width: Int, height: Int) {
        switch resolution {
        case .hd720: return (1280, 720)
        case .hd1080: return (1920, 1080)
        case .uhd4k: return (3840, 2160)
        }
    }

    /// The format to use: exactly the resolution, able to run at `fps`, full-range 420 when one
    /// is; its index in `formats`, or the reason none fits.
    public static func chooseFormat(_ formats: [CameraFormatInfo], resolution: Resolution, fps: UInt32) throws -> Int {
        let (width, height) = dimensions(of: resolution)
        let rate = Double(fps)
        let matching = formats.indices.filter { i in
            formats[i].width == width && formats[i].height == height && formats[i].frameRates.contains { $0.contains(rate) }
        }
        guard let chosen = matching.first(where: { formats[$0].fullRange420 }) ?? matching.first else {
            throw AppError(message: "This camera cannot film \(width)×\(height) at \(fps) fps; choose another resolution or frame rate.")
        }
        return chosen
    }

    /// A column-major pinhole matrix (as AVFoundation's) from the horizontal field of view,
    /// principal point at the centre.
    public static func pinholeMatrix(width: UInt32, height: UInt32, fieldOfViewDegrees: Float) -> [Float] {
        let halfAngle = Double(fieldOfViewDegrees) * Double.pi / 360
        let focal = Float(Double(width) / 2 / tan(halfAngle))
        return [focal, 0, 0, 0, focal, 0, Float(width) / 2, Float(height) / 2, 1]
    }

    /// The camera's name for people.
    public static func title(of camera: Camera) -> String {
        switch camera {
        case .backWide: return "back wide"
        case .backTele: return "back telephoto"
        case .front: return "front"
        }
    }

    /// The message when the phone lacks the chosen camera.
    public static func missingCamera(_ camera: Camera) -> AppError {
        AppError(message: "This iPhone has no \(title(of: camera)) camera.")
    }

    /// The nine numbers (column-major) of AVFoundation's per-frame intrinsic matrix attachment,
    /// a `matrix_float3x3` in a CFData: three columns of a `simd_float3` each, and a
    /// `simd_float3` takes 16 bytes (the fourth lane is padding), so 48 bytes, not 36. Nil when
    /// the data is too short or not finite.
    public static func cameraMatrix(fromAttachment data: Data?) -> [Float]? {
        guard let data, data.count >= 48 else {
            return nil
        }
        let bytes = [UInt8](data.prefix(48))
        let matrix = (0..<3).flatMap { column in
            (0..<3).map { row -> Float in
                let at = column * 16 + row * 4
                let bits = (0..<4).reduce(UInt32(0)) { $0 | UInt32(bytes[at + $1]) << (8 * UInt32($1)) }
                return Float(bitPattern: bits)
            }
        }
        return matrix.allSatisfy(\.isFinite) ? matrix : nil
    }

    /// The frame's intrinsics in its own pixels: the delivered matrix when there is one (scaled
    /// from the active format to the frame by the library), else the field-of-view estimate.
    public static func intrinsics(
        cameraMatrix: [Float]?,
        configuration: CaptureConfiguration,
        width: Int,
        height: Int
    ) throws -> (intrinsics: Intrinsics, estimated: Bool) {
        let intrinsics = try intrinsicsFromCameraMatrix(
            matrix: cameraMatrix ?? configuration.estimatedMatrix,
            referenceWidth: configuration.referenceWidth,
            referenceHeight: configuration.referenceHeight,
            width: UInt32(clamping: width),
            height: UInt32(clamping: height)
        )
        return (intrinsics, cameraMatrix == nil)
    }
}

extension CameraPlanner {
    /// The codec the movie is written with, among the four-character codes the capture output
    /// offers for a .mov: HEVC (`hvc1`) when offered, else H.264 (`avc1`), else none.
    public static func videoCodec(among available: [String]) -> String? {
        ["hvc1", "avc1"].first { available.contains($0) }
    }
}
