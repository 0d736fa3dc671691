// Adapts SwiftUI's ObservableObject to JawTrackKit's AppController: builds it over the Apple
// adapters (UserDefaults, Keychain, camera, Documents, UDP) and publishes its ScreenState and
// the marker calibration's CalibrationScreen.
import AVFoundation
import JawTrackKit
import UIKit

@MainActor
final class AppModel: ObservableObject {
    @Published private(set) var state: ScreenState
    @Published private(set) var calibration: CalibrationScreen
    let camera: CameraController
    /// The screen's logic: the views call it for every action.
    let controller: AppController

    init() {
        let camera = CameraController()
        let controller = AppController(
            settings: SettingsStore(
                values: UserDefaultsStore(), secrets: KeychainStore(), performanceCores: Self.performanceCores()
            ),
            camera: camera,
            documents: FileManager.default.urls(for: .documentDirectory, in: .userDomainMask).first,
            makeTransport: { host, port in try UDPTransport(host: host, port: port) }
        )
        self.camera = camera
        self.controller = controller
        state = controller.state
        calibration = controller.markerCalibration.state
        controller.onChange = { [weak self] in self?.state = $0 }
        controller.markerCalibration.onChange = { [weak self] in self?.calibration = $0 }
    }

    /// The phone's performance cores (`hw.perflevel0.physicalcpu`, iOS 15 and later), 0 when the
    /// system does not say.
    private static func performanceCores() -> UInt32 {
        var cores: Int32 = 0
        var size = MemoryLayout<Int32>.size
        guard sysctlbyname("hw.perflevel0.physicalcpu", &cores, &size, nil, 0) == 0, cores > 0 else {
            return 0
        }
        return UInt32(cores)
    }

    /// First appearance: the screen stays on; the camera permission (asked the first time,
    /// answered at once after), then the controller starts.
    func start() {
        UIApplication.shared.isIdleTimerDisabled = true
        Task {
            let allowed = await AVCaptureDevice.requestAccess(for: .video)
            controller.start(cameraAllowed: allowed)
        }
    }
}
