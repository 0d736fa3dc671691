import Foundation
import JawTrackCore

/// The settings screen's values, kept between launches: the pairing key in the Keychain, the
/// rest in UserDefaults as `StoredSettings` (uniffi records are not Codable). What is valid is
/// decided by the library (`validateAppSettings`), not here.
@MainActor
final class SettingsStore: ObservableObject {
    @Published private(set) var settings: AppSettings
    /// Why the saved settings could not all be read at launch (the defaults were used instead).
    private(set) var loadProblem: String?

    private let defaults: UserDefaults
    private static let defaultsKey = "org.jawtrack.settings.v1"

    init(defaults: UserDefaults = .standard) {
        self.defaults = defaults
        var loaded = defaultAppSettings()
        var problem: String?
        if let data = defaults.data(forKey: Self.defaultsKey) {
            do {
                loaded = try JSONDecoder().decode(StoredSettings.self, from: data).applied(to: loaded)
            } catch {
                problem = "The saved settings could not be read; the defaults are used. (\(error.localizedDescription))"
            }
        }
        do {
            loaded.pairingKey = try PairingKeychain.load()
        } catch {
            problem = userText(error)
        }
        settings = loaded
        loadProblem = problem
    }

    /// Stores `new` (the caller has validated it).
    func save(_ new: AppSettings) throws {
        let data = try JSONEncoder().encode(StoredSettings(new))
        try PairingKeychain.save(new.pairingKey)
        defaults.set(data, forKey: Self.defaultsKey)
        settings = new
    }
}

/// `AppSettings` without the pairing key, in a Codable form: what UserDefaults keeps and what a
/// recording's header says about the settings it was made with.
struct StoredSettings: Codable {
    var camera: String
    var resolution: String
    var fps: UInt32
    var focus: String
    var lensPosition: Float
    var exposureLocked: Bool
    var bgra: Bool
    var decimate: Float
    var quadSigma: Float
    var maxHamming: UInt32
    var threads: UInt32
    var linearEdges: Bool
    var regionSearch: Bool
    var smooth: Bool
    var receiverHost: String
    var receiverPort: UInt32
    var recordVideo: Bool

    init(_ settings: AppSettings) {
        camera = Self.name(of: settings.camera)
        resolution = Self.name(of: settings.resolution)
        fps = settings.fps
        focus = Self.name(of: settings.focus)
        lensPosition = settings.lensPosition
        exposureLocked = settings.exposureLocked
        bgra = settings.bgra
        decimate = settings.tracker.decimate
        quadSigma = settings.tracker.quadSigma
        maxHamming = settings.tracker.maxHamming
        threads = settings.tracker.threads
        linearEdges = settings.tracker.linearEdges
        regionSearch = settings.tracker.regionSearch
        smooth = settings.tracker.smooth
        receiverHost = settings.receiverHost
        receiverPort = settings.receiverPort
        recordVideo = settings.recordVideo
    }

    /// These values over `base` (whose pairing key is kept); unknown names keep `base`'s choice.
    func applied(to base: AppSettings) -> AppSettings {
        let tracker = JawTrackCore.Settings(
            decimate: decimate,
            quadSigma: quadSigma,
            maxHamming: maxHamming,
            threads: threads,
            linearEdges: linearEdges,
            regionSearch: regionSearch,
            smooth: smooth
        )
        return AppSettings(
            camera: Self.camera(named: camera) ?? base.camera,
            resolution: Self.resolution(named: resolution) ?? base.resolution,
            fps: fps,
            focus: Self.focus(named: focus) ?? base.focus,
            lensPosition: lensPosition,
            exposureLocked: exposureLocked,
            bgra: bgra,
            tracker: tracker,
            receiverHost: receiverHost,
            receiverPort: receiverPort,
            pairingKey: base.pairingKey,
            recordVideo: recordVideo
        )
    }

    /// As JSON with snake_case keys, for a recording's header.
    func headerJSON() -> String? {
        let encoder = JSONEncoder()
        encoder.keyEncodingStrategy = .convertToSnakeCase
        encoder.outputFormatting = [.sortedKeys]
        guard let data = try? encoder.encode(self) else {
            return nil
        }
        return String(decoding: data, as: UTF8.self)
    }

    private static func name(of camera: Camera) -> String {
        switch camera {
        case .backWide: return "back_wide"
        case .backTele: return "back_tele"
        case .front: return "front"
        }
    }

    private static func camera(named name: String) -> Camera? {
        switch name {
        case "back_wide": return .backWide
        case "back_tele": return .backTele
        case "front": return .front
        default: return nil
        }
    }

    private static func name(of resolution: Resolution) -> String {
        switch resolution {
        case .hd720: return "720p"
        case .hd1080: return "1080p"
        case .uhd4k: return "4k"
        }
    }

    private static func resolution(named name: String) -> Resolution? {
        switch name {
        case "720p": return .hd720
        case "1080p": return .hd1080
        case "4k": return .uhd4k
        default: return nil
        }
    }

    private static func name(of focus: FocusMode) -> String {
        switch focus {
        case .auto: return "auto"
        case .manual: return "manual"
        }
    }

    private static func focus(named name: String) -> FocusMode? {
        switch name {
        case "auto": return .auto
        case "manual": return .manual
        default: return nil
        }
    }
}
