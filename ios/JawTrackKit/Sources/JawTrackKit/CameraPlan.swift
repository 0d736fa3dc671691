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
    /// The zoom factors at which the format crops the sensor at its native resolution
    /// (`secondaryNativeResolutionZoomFactors`, iOS 16; empty when none): a 2× crop of a 48 MP
    /// sensor films 1080p from unbinned pixels.
    public let nativeZooms: [Double]

    public init(
        width: Int, height: Int, frameRates: [ClosedRange<Double>], fullRange420: Bool, fieldOfViewDegrees: Float,
        maxISO: Float = 0, nativeZooms: [Double] = []
    ) {
        self.width = width
        self.height = height
        self.frameRates = frameRates
        self.fullRange420 = fullRange420
        self.fieldOfViewDegrees = fieldOfViewDegrees
        self.maxISO = maxISO
        self.nativeZooms = nativeZooms
    }

    /// The format as the library's capture planner takes it.
    public var captureFormat: CaptureFormat {
        CaptureFormat(
            width: UInt32(clamping: width), height: UInt32(clamping: height),
            maxFps: frameRates.map(\.upperBound).max() ?? 0, fovDeg: Double(fieldOfViewDegrees), nativeZooms: nativeZooms
        )
    }
}

/// One camera of the phone as the camera layer reports it before it is configured (from
/// `AVCaptureDevice`): what the capture plan and the format choice are decided from.
public struct CameraDevice: Equatable {
    /// The hardware model, e.g. "iPhone16,1".
    public let model: String
    public let camera: Camera
    /// The nearest distance the lens focuses at (mm), as the device reports it; nil when it
    /// does not know.
    public let minimumFocusMm: Double?
    public let formats: [CameraFormatInfo]

    public init(model: String, camera: Camera, minimumFocusMm: Double?, formats: [CameraFormatInfo]) {
        self.model = model
        self.camera = camera
        self.minimumFocusMm = minimumFocusMm
        self.formats = formats
    }

    /// AVFoundation's `minimumFocusDistance` (mm; -1 when unknown) as `minimumFocusMm`.
    public static func focusDistance(reported millimetres: Int) -> Double? {
        millimetres > 0 ? Double(millimetres) : nil
    }
}

/// How the focus is to be set.
public enum FocusPlan: Equatable {
    case continuousAuto
    /// Locked at a lens position (0 near … 1 far).
    case locked(lensPosition: Float)
    /// The capture plan's: continuous autofocus on the centre of the frame (smooth autofocus
    /// off, so it settles fast) until the controller locks it where it settled
    /// (`CameraControl.lockFocus`), which it does once the phone is held still at the plan's
    /// distance. Every new session starts focusing again.
    case continuousAutoUntilLocked
}

/// How the camera is to be set for measuring, from the settings (and in focus mode planned the
/// capture plan's zoom, `CaptureSetup`). The camera layer applies it and decides nothing:
/// metrology needs frames as the sensor gives them (no stabilisation warp, no HDR tone mapping
/// that changes between frames, no zoom that upscales), the intrinsic matrix per frame, a focus
/// that stays put while recording, and on demand an exposure and white balance that stay put.
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
    /// `videoZoomFactor`: 1, or the capture plan's native crop (focus mode planned). A digital
    /// zoom that upscales is never asked for.
    public let zoomFactor: Double
    /// Seconds a frame lasts at the chosen rate.
    public var frameDuration: Double { 1 / Double(fps) }

    /// `zoomFactor`: the capture plan's zoom in focus mode planned (`CaptureSetup`), else 1.
    public init(_ settings: AppSettings, zoomFactor: Double = 1) {
        layout = settings.bgra ? .bgra : .luma
        fps = settings.fps
        switch settings.focus {
        case .auto: focus = .continuousAuto
        case .manual: focus = .locked(lensPosition: min(max(settings.lensPosition, 0), 1))
        case .planned: focus = .continuousAutoUntilLocked
        }
        lockExposureAfter = settings.exposureLocked ? 1 : nil
        maxExposure = settings.maxExposureS > 0 ? settings.maxExposureS : nil
        self.zoomFactor = settings.focus == .planned ? zoomFactor : 1
    }
}

/// What the camera is configured with, decided from the camera's description and the settings:
/// in focus mode planned, the library's capture plan (`CapturePlanner`, for the marker tracked
/// and the frame rate set) chooses the format's size and the zoom, and the phone is then guided
/// to the plan's distance and focus locked there; otherwise the resolution setting chooses the
/// format, at zoom 1. Either way the format is one of exactly that size that runs at the frame
/// rate, full-range 420 when there is one.
public struct CaptureSetup {
    public let device: CameraDevice
    public let plan: CapturePlan
    /// The chosen format: its index in `device.formats`.
    public let formatIndex: Int
    /// The capture plan (focus mode planned only).
    public let planner: CapturePlanner?
    /// The plan as shown and applied (focus mode planned only).
    public let choice: PlanChoice?

    /// `markerJSON`: the marker file the tracker uses (nil: the nominal marker). Throws the
    /// library's reason when no plan fits, or the format choice's.
    public init(device: CameraDevice, settings: AppSettings, markerJSON: String?) throws {
        self.device = device
        guard settings.focus == .planned else {
            formatIndex = try CameraPlanner.chooseFormat(
                device.formats, resolution: settings.resolution, fps: settings.fps
            )
            plan = CapturePlan(settings)
            planner = nil
            choice = nil
            return
        }
        let planner = try CapturePlanner(
            model: device.model, camera: device.camera, reportedMinFocusMm: device.minimumFocusMm,
            formats: device.formats.map(\.captureFormat), fps: settings.fps, markerJson: markerJSON
        )
        let choice = planner.choice()
        formatIndex = try CameraPlanner.chooseFormat(
            device.formats, width: Int(choice.width), height: Int(choice.height), fps: settings.fps, zoom: choice.zoom
        )
        plan = CapturePlan(settings, zoomFactor: choice.zoom)
        self.planner = planner
        self.choice = choice
    }

    /// The chosen format.
    public var format: CameraFormatInfo { device.formats[formatIndex] }

    /// What the frame pipeline knows of the camera once configured.
    public var configuration: CaptureConfiguration {
        CaptureConfiguration(format: format, plan: plan, model: device.model, camera: device.camera)
    }
}

/// What the frame pipeline knows of the camera as configured.
public struct CaptureConfiguration: Equatable {
    /// The active format's size: what the delivered intrinsic matrix refers to.
    public let referenceWidth: UInt32
    public let referenceHeight: UInt32
    /// A pinhole matrix from the format's field of view and the zoom (same layout as the
    /// delivered one), for frames that arrive without one.
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
            width: referenceWidth, height: referenceHeight, fieldOfViewDegrees: format.fieldOfViewDegrees,
            zoom: plan.zoomFactor
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
        guard let chosen = bestFormat(formats, width: width, height: height, fps: fps, zoom: 1) else {
            throw AppError(message: "This camera cannot film \(width)×\(height) at \(fps) fps; choose another resolution or frame rate.")
        }
        return chosen
    }

    /// The capture plan's format: exactly `width`×`height`, able to run at `fps`, cropping
    /// natively at `zoom` when it is above 1 (`nativeZooms`), full-range 420 when one is; its
    /// index in `formats`, or the reason none fits.
    public static func chooseFormat(
        _ formats: [CameraFormatInfo], width: Int, height: Int, fps: UInt32, zoom: Double
    ) throws -> Int {
        guard let chosen = bestFormat(formats, width: width, height: height, fps: fps, zoom: zoom) else {
            throw AppError(
                message: "This camera cannot film \(width)×\(height) at \(fps) fps as its capture plan asks; "
                    + "choose another frame rate or focus mode."
            )
        }
        return chosen
    }

    /// Among the formats of the size that run at `fps` (and, for a zoom above 1, crop natively
    /// at it: a zoom that upscales is not taken), full-range 420 first.
    private static func bestFormat(
        _ formats: [CameraFormatInfo], width: Int, height: Int, fps: UInt32, zoom: Double
    ) -> Int? {
        let rate = Double(fps)
        let matching = formats.indices.filter { i in
            formats[i].width == width && formats[i].height == height && formats[i].frameRates.contains { $0.contains(rate) }
                && (zoom == 1 || formats[i].nativeZooms.contains { abs($0 - zoom) < 1e-6 })
        }
        return matching.first(where: { formats[$0].fullRange420 }) ?? matching.first
    }

    /// A column-major pinhole matrix (as AVFoundation's) from the horizontal field of view at
    /// zoom 1 and the zoom (a crop of the centre: the focal length in pixels grows with it),
    /// principal point at the centre.
    public static func pinholeMatrix(width: UInt32, height: UInt32, fieldOfViewDegrees: Float, zoom: Double = 1) -> [Float] {
        let halfAngle = Double(fieldOfViewDegrees) * Double.pi / 360
        let focal = Float(Double(width) / 2 / tan(halfAngle) * zoom)
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
