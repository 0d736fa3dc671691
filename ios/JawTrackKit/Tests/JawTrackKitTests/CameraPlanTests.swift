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
        var plan = CapturePlan(settings)
        XCTAssertFalse(plan.videoHDR)
        XCTAssertFalse(plan.stabilization)
        XCTAssertTrue(plan.intrinsicMatrixDelivery)
        XCTAssertTrue(plan.discardLateFrames)
        XCTAssertNil(plan.lockExposureAfter)
        XCTAssertEqual(plan.layout, .luma)
        XCTAssertEqual(plan.focus, .continuousAuto)
        settings.exposureLocked = true
        settings.bgra = true
        settings.focus = .manual
        settings.lensPosition = 1.7
        settings.fps = 60
        plan = CapturePlan(settings)
        XCTAssertEqual(plan.lockExposureAfter, 1)
        XCTAssertEqual(plan.layout, .bgra)
        XCTAssertEqual(plan.focus, .locked(lensPosition: 1))
        XCTAssertEqual(plan.frameDuration, 1.0 / 60)
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
}
