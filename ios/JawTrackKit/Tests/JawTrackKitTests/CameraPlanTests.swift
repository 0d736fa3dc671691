import Foundation
import JawTrackCore
import JawTrackKit
import XCTest

/// The camera decisions: format, metrology settings, estimated intrinsics, overlay geometry.
final class CameraPlanTests: XCTestCase {
    private let formats = [
        CameraFormatInfo(width: 1920, height: 1080, frameRates: [1...30], fullRange420: false, fieldOfViewDegrees: 70),
        CameraFormatInfo(width: 1920, height: 1080, frameRates: [1...60], fullRange420: false, fieldOfViewDegrees: 70),
        CameraFormatInfo(width: 1920, height: 1080, frameRates: [1...60], fullRange420: true, fieldOfViewDegrees: 70),
        CameraFormatInfo(width: 3840, height: 2160, frameRates: [1...30], fullRange420: true, fieldOfViewDegrees: 70),
    ]

    func testTheFormatIsExactlyTheResolutionAtTheRateFullRangeFirst() throws {
        XCTAssertEqual(try CameraPlanner.chooseFormat(formats, resolution: .hd1080, fps: 60), 2)
        XCTAssertEqual(try CameraPlanner.chooseFormat(Array(formats.prefix(2)), resolution: .hd1080, fps: 60), 1)
        XCTAssertEqual(try CameraPlanner.chooseFormat(formats, resolution: .uhd4k, fps: 30), 3)
        XCTAssertThrowsError(try CameraPlanner.chooseFormat(formats, resolution: .uhd4k, fps: 60)) {
            XCTAssertEqual(userText($0), "This camera cannot film 3840×2160 at 60 fps; choose another resolution or frame rate.")
        }
        XCTAssertThrowsError(try CameraPlanner.chooseFormat(formats, resolution: .hd720, fps: 30))
    }

    func testThePlanIsForMeasuring() {
        var settings = defaultAppSettings()
        XCTAssertEqual(settings.focus, .planned, "the default")
        var plan = CapturePlan(settings)
        XCTAssertFalse(plan.videoHDR)
        XCTAssertFalse(plan.stabilization)
        XCTAssertTrue(plan.intrinsicMatrixDelivery)
        XCTAssertTrue(plan.discardLateFrames)
        XCTAssertNil(plan.lockExposureAfter)
        XCTAssertEqual(plan.layout, .luma)
        XCTAssertEqual(plan.focus, .continuousAutoUntilLocked)
        XCTAssertEqual(CapturePlan(settings, zoomFactor: 2).zoomFactor, 2, "the capture plan's native crop")
        settings.focus = .auto
        plan = CapturePlan(settings, zoomFactor: 2)
        XCTAssertEqual(plan.focus, .continuousAuto)
        XCTAssertEqual(plan.zoomFactor, 1, "zoom 1 unless planned")
        settings.exposureLocked = true
        settings.bgra = true
        settings.focus = .manual
        settings.lensPosition = 1.7
        settings.fps = 60
        plan = CapturePlan(settings)
        XCTAssertEqual(plan.lockExposureAfter, 1)
        XCTAssertEqual(plan.layout, .bgra)
        XCTAssertEqual(plan.focus, .locked(lensPosition: 1))
        XCTAssertEqual(plan.zoomFactor, 1)
        XCTAssertEqual(plan.frameDuration, 1.0 / 60)
    }

    /// The wide camera's 1080p and 4K formats as a phone lists them (video range, then full
    /// range), with `nativeZooms`.
    private func phoneFormats(nativeZooms: [Double]) -> [CameraFormatInfo] {
        [(1920, 1080), (3840, 2160)].flatMap { width, height in
            [false, true].map { fullRange in
                CameraFormatInfo(
                    width: width, height: height, frameRates: [1...60], fullRange420: fullRange, fieldOfViewDegrees: 70,
                    nativeZooms: nativeZooms
                )
            }
        }
    }

    func testAProPhoneIsPlannedAt1080pWithItsNativeCrop() throws {
        let device = CameraDevice(model: "iPhone16,1", camera: .backWide, minimumFocusMm: 200, formats: phoneFormats(nativeZooms: [2]))
        var settings = defaultAppSettings()
        settings.resolution = .uhd4k
        let setup = try CaptureSetup(device: device, settings: settings, markerJSON: nil)
        XCTAssertEqual(setup.formatIndex, 1, "1080p, full range; the resolution setting is not used")
        XCTAssertEqual(setup.plan.zoomFactor, 2)
        XCTAssertEqual(setup.plan.focus, .continuousAutoUntilLocked)
        XCTAssertEqual(setup.plan.fps, 60)
        XCTAssertNotNil(setup.planner)
        let choice = try XCTUnwrap(setup.choice)
        XCTAssertEqual([choice.width, choice.height, choice.fps], [1920, 1080, 60])
        XCTAssertEqual(choice.zoom, 2)
        XCTAssertEqual(choice.distanceMm, 220)
        XCTAssertTrue(choice.summary.contains("2× native crop"), choice.summary)
        XCTAssertTrue(choice.notes.isEmpty, "the phone reported its nearest focus: \(choice.notes)")
        let configuration = setup.configuration
        XCTAssertEqual(configuration.referenceWidth, 1920)
        XCTAssertEqual(configuration.deviceDescription, "iPhone16,1 back wide")
        XCTAssertEqual(
            configuration.estimatedMatrix[0], 2 * CameraPlanner.pinholeMatrix(width: 1920, height: 1080, fieldOfViewDegrees: 70)[0],
            accuracy: 1e-2, "the estimate's focal length is the crop's"
        )
        let marker = try Tracker(settings: defaultSettings(), markerJson: nil).markerJson()
        XCTAssertEqual(try CaptureSetup(device: device, settings: settings, markerJSON: marker).choice, choice,
                       "the tracker's marker: the nominal one")
    }

    func testATwelveMegapixelPhoneIsPlannedAt4K() throws {
        let device = CameraDevice(
            model: "iPhone14,2", camera: .backWide, minimumFocusMm: CameraDevice.focusDistance(reported: -1),
            formats: phoneFormats(nativeZooms: [])
        )
        XCTAssertNil(device.minimumFocusMm, "AVFoundation's -1: not known")
        let setup = try CaptureSetup(device: device, settings: defaultAppSettings(), markerJSON: nil)
        XCTAssertEqual(setup.formatIndex, 3, "4K, full range")
        XCTAssertEqual(setup.plan.zoomFactor, 1)
        let choice = try XCTUnwrap(setup.choice)
        XCTAssertEqual([choice.width, choice.height], [3840, 2160])
        XCTAssertFalse(choice.notes.isEmpty, "the nearest focus did not come from the phone: the plan says where from")
    }

    func testOtherFocusModesChooseByTheResolutionAtZoomOne() throws {
        let device = CameraDevice(model: "iPhone16,1", camera: .backWide, minimumFocusMm: 200, formats: phoneFormats(nativeZooms: [2]))
        var settings = defaultAppSettings()
        settings.focus = .auto
        settings.resolution = .uhd4k
        let setup = try CaptureSetup(device: device, settings: settings, markerJSON: nil)
        XCTAssertEqual(setup.formatIndex, 3)
        XCTAssertEqual(setup.plan.zoomFactor, 1)
        XCTAssertNil(setup.planner)
        XCTAssertNil(setup.choice)
        XCTAssertEqual(setup.configuration.estimatedMatrix, CameraPlanner.pinholeMatrix(width: 3840, height: 2160, fieldOfViewDegrees: 70))
        settings.focus = .manual
        settings.resolution = .hd720
        XCTAssertThrowsError(try CaptureSetup(device: device, settings: settings, markerJSON: nil)) {
            XCTAssertEqual(userText($0), "This camera cannot film 1280×720 at 60 fps; choose another resolution or frame rate.")
        }
    }

    func testThePlansFormatCropsNativelyAndTheCameraIsDescribedAsThePlannerTakesIt() throws {
        let formats = [
            CameraFormatInfo(width: 1920, height: 1080, frameRates: [1...30, 1...60], fullRange420: true, fieldOfViewDegrees: 70),
            CameraFormatInfo(width: 1920, height: 1080, frameRates: [1...60], fullRange420: false, fieldOfViewDegrees: 70, nativeZooms: [2]),
        ]
        XCTAssertEqual(try CameraPlanner.chooseFormat(formats, width: 1920, height: 1080, fps: 60, zoom: 2), 1,
                       "the one that crops at 2× natively, though video range")
        XCTAssertEqual(try CameraPlanner.chooseFormat(formats, width: 1920, height: 1080, fps: 60, zoom: 1), 0)
        XCTAssertThrowsError(try CameraPlanner.chooseFormat(Array(formats.prefix(1)), width: 1920, height: 1080, fps: 60, zoom: 2),
                             "a zoom that upscales is not taken")
        XCTAssertEqual(formats[1].captureFormat, CaptureFormat(width: 1920, height: 1080, maxFps: 60, fovDeg: 70, nativeZooms: [2]))
        XCTAssertEqual(formats[0].captureFormat.maxFps, 60)
        XCTAssertEqual(CameraDevice.focusDistance(reported: 200), 200)
        XCTAssertNil(CameraDevice.focusDistance(reported: 0))
    }

    func testTheEstimatedMatrixComesFromTheFieldOfView() throws {
        let matrix = CameraPlanner.pinholeMatrix(width: 1920, height: 1080, fieldOfViewDegrees: 90)
        XCTAssertEqual(matrix[0], 960, accuracy: 1e-3)
        XCTAssertEqual(matrix[4], 960, accuracy: 1e-3)
        XCTAssertEqual(matrix[6], 960)
        XCTAssertEqual(matrix[7], 540)
        let configuration = CaptureConfiguration(format: formats[2], plan: CapturePlan(defaultAppSettings()), model: "iPhone15,2", camera: .backWide)
        XCTAssertEqual(configuration.deviceDescription, "iPhone15,2 back wide")
        let (intrinsics, estimated) = try CameraPlanner.intrinsics(cameraMatrix: nil, configuration: configuration, width: 1920, height: 1080)
        XCTAssertTrue(estimated)
        XCTAssertEqual(intrinsics.cx, 959.5)
        XCTAssertEqual(intrinsics.fx, 1920 / 2 / tan(35 * Double.pi / 180), accuracy: 1e-2)
    }

    func testOverlayPointsThatAreNotFiniteAreLeftOut() {
        let overlay = Overlay(
            tags: [
                TagOverlay(id: 3, body: "maxilla", corners: [0.1, 0.1, 0.2, 0.1, 0.2, 0.2, 0.1, 0.2], center: [0.15, 0.15]),
                TagOverlay(id: 4, body: "maxilla", corners: [0.1, .nan, 0.2, 0.1, 0.2, 0.2, 0.1, 0.2], center: [0.15, 0.15]),
                TagOverlay(id: 14, body: "mandible", corners: [0.1, 0.1], center: [0.15, 0.15]),
            ],
            axes: [AxisOverlay(body: "maxilla", origin: [0.5, 0.5], ends: [0.6, 0.5, 0.5, 0.6, .infinity, 0.5])]
        )
        let geometry = OverlayGeometry(overlay) { ViewPoint(x: $0.x * 100, y: $0.y * 200) }
        XCTAssertEqual(geometry.outlines["maxilla"]?.count, 1)
        XCTAssertNil(geometry.outlines["mandible"])
        XCTAssertEqual(geometry.labels, [OverlayGeometry.Label(text: "3", origin: ViewPoint(x: -1, y: 21), width: 32, height: 18)])
        XCTAssertEqual(geometry.axes.map(\.count), [1, 1, 0])
        XCTAssertEqual(geometry.axes[0][0].1, ViewPoint(x: 60, y: 100))
        XCTAssertEqual(OverlayGeometry(nil) { $0 }, OverlayGeometry())
    }

    func testTheAppleLayerAsksForTheFormatsAndCodecDecidedHere() {
        XCTAssertEqual(FrameDoor.fourCharacterCode(PixelLayout.luma.pixelFormat), "420f")
        XCTAssertEqual(FrameDoor.fourCharacterCode(PixelLayout.bgra.pixelFormat), "BGRA")
        XCTAssertEqual(PixelLayout(pixelFormat: PixelLayout.bgra.pixelFormat), .bgra)
        XCTAssertNil(PixelLayout(pixelFormat: 0x3432_3076), "420v (video range) is not read as luma")
        XCTAssertEqual(CameraPlanner.videoCodec(among: ["avc1", "hvc1", "jpeg"]), "hvc1")
        XCTAssertEqual(CameraPlanner.videoCodec(among: ["jpeg", "avc1"]), "avc1")
        XCTAssertNil(CameraPlanner.videoCodec(among: ["jpeg"]))
    }

    func testTheOverlaysStrokesCloseEachOutline() {
        let overlay = Overlay(
            tags: [TagOverlay(id: 14, body: "mandible", corners: [0.1, 0.1, 0.2, 0.1, 0.2, 0.2, 0.1, 0.2], center: [0.15, 0.15])],
            axes: [AxisOverlay(body: "mandible", origin: [0.5, 0.5], ends: [0.6, 0.5, 0.5, 0.6, 0.55, 0.55])]
        )
        let strokes = OverlayGeometry(overlay) { $0 }.strokes
        XCTAssertEqual(strokes.count, OverlayGeometry.strokeWidths.count)
        XCTAssertTrue(strokes[0].isEmpty, "no maxilla tag")
        XCTAssertEqual(strokes[1].count, 1)
        XCTAssertEqual(strokes[1][0].count, 5)
        XCTAssertEqual(strokes[1][0].first, strokes[1][0].last)
        XCTAssertEqual(strokes[4], [[ViewPoint(x: 0.5, y: 0.5), ViewPoint(x: 0.55, y: 0.55)]])
    }

    func testTheSettingsRangesInTheControlsTypes() {
        XCTAssertEqual(SettingsForm.quadSigma.floats, 0...0.8)
        XCTAssertEqual(SettingsForm.quadSigma.text(0.4), "0.4")
        XCTAssertEqual(SettingsForm.threads.counts, 1...8)
        XCTAssertEqual(SettingsForm.threads.countStep, 1)
        XCTAssertEqual(SettingsForm.threads.text(3), "Threads: 3")
        XCTAssertEqual(SettingsForm.lensPosition.floatStep, 0.01)
    }

    func testPlatformRefusalsAreWordedHere() {
        XCTAssertEqual(PlatformText.keychain(status: -25308, text: nil).message, "Keychain: error -25308")
        XCTAssertEqual(PlatformText.keychain(status: -25308, text: "User interaction is not allowed.").message,
                       "Keychain: User interaction is not allowed.")
        XCTAssertEqual(PlatformText.pixelFormatUnavailable(.luma).message, "This camera does not deliver 420f frames.")
        XCTAssertEqual(PlatformText.noManualFocus(.front).message, "The front camera has no manual focus; choose auto.")
        XCTAssertEqual(PlatformText.focusNotLocked(AppError(message: "busy")),
                       "busy. Focus mode Planned records only with the focus locked: leave the app and come back to try again, or choose Auto focus in Settings.")
        XCTAssertFalse(PlatformText.formatUnavailable.message.isEmpty)
        XCTAssertTrue(PlatformText.exposureNotLocked(AppError(message: "busy")).hasSuffix("busy"))
    }

    func testTheIntrinsicMatrixAttachmentIsReadWithItsPaddedColumns() {
        func bytes(_ columns: [[Float]]) -> Data {
            var data = Data()
            for column in columns {
                for value in column + [Float.nan] {
                    data += withUnsafeBytes(of: value.bitPattern.littleEndian) { Data($0) }
                }
            }
            return data
        }
        let attachment = bytes([[1500, 0, 0], [0, 1501, 0], [960, 540, 1]])
        XCTAssertEqual(attachment.count, 48)
        XCTAssertEqual(CameraPlanner.cameraMatrix(fromAttachment: attachment), [1500, 0, 0, 0, 1501, 0, 960, 540, 1])
        XCTAssertNil(CameraPlanner.cameraMatrix(fromAttachment: attachment.prefix(36)), "a packed 3×3 is not the layout")
        XCTAssertNil(CameraPlanner.cameraMatrix(fromAttachment: nil))
        XCTAssertNil(CameraPlanner.cameraMatrix(fromAttachment: bytes([[.infinity, 0, 0], [0, 1, 0], [0, 0, 1]])))
    }
}
