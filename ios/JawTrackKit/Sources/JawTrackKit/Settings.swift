import Foundation
import JawTrackCore

/// A small key-value store (UserDefaults in the app, a dictionary in tests).
public protocol KeyValueStore: AnyObject {
    func data(forKey key: String) -> Data?
    func set(_ data: Data, forKey key: String)
}

/// Where the pairing key is kept (the Keychain, this device only, in the app): it seals the
/// stream, so it stays out of the key-value store, backups in clear and recordings (which carry
/// only its id).
public protocol SecretStore: AnyObject {
    /// The stored key, or "" when none is.
    func load() throws -> String
    /// Replaces the stored key; "" removes it.
    func save(_ key: String) throws
}

/// A key-value store in memory.
public final class MemoryKeyValueStore: KeyValueStore {
    public private(set) var values: [String: Data] = [:]

    public init() {}

    public func data(forKey key: String) -> Data? { values[key] }

    public func set(_ data: Data, forKey key: String) { values[key] = data }
}

/// A secret store in memory.
public final class MemorySecretStore: SecretStore {
    public var secret = ""
    /// Set to make every call fail with this message (as a locked Keychain would).
    public var failure: String?

    public init() {}

    public func load() throws -> String {
        if let failure {
            throw AppError(message: "Keychain: \(failure)")
        }
        return secret
    }

    public func save(_ key: String) throws {
        if let failure {
            throw AppError(message: "Keychain: \(failure)")
        }
        secret = key
    }
}

/// The settings, kept between launches: the pairing key in the secret store, the rest in the
/// key-value store as `StoredSettings` (uniffi records are not Codable). What is valid is the
/// library's call (`validateAppSettings`): nothing invalid is saved.
public final class SettingsStore {
    public static let key = "org.jawtrack.settings.v1"

    public private(set) var settings: AppSettings
    /// Why the saved settings could not all be read at launch (the defaults were used instead).
    public let loadProblem: String?

    private let values: KeyValueStore
    private let secrets: SecretStore

    /// `performanceCores`: the phone's performance cores (0 when the system does not say); a
    /// fresh install runs a detector thread on each (`detectorThreads`).
    public init(values: KeyValueStore, secrets: SecretStore, performanceCores: UInt32 = 0) {
        self.values = values
        self.secrets = secrets
        var loaded = defaultAppSettings()
        loaded.tracker.threads = detectorThreads(performanceCores: performanceCores)
        var problems: [String] = []
        if let data = values.data(forKey: Self.key) {
            do {
                let candidate = try JSONDecoder().decode(StoredSettings.self, from: data).applied(to: loaded)
                try validateAppSettings(settings: candidate, streaming: false)
                loaded = candidate
            } catch {
                problems.append("The saved settings could not be used; the defaults are. (\(Self.describe(error)))")
            }
        }
        do {
            loaded.pairingKey = try secrets.load()
        } catch {
            problems.append(userText(error))
        }
        settings = loaded
        loadProblem = problems.isEmpty ? nil : problems.joined(separator: " ")
    }

    /// Validates `new` with the library and stores it; throws the library's refusal or the
    /// store's error, and then keeps the old settings.
    public func save(_ new: AppSettings) throws {
        try validateAppSettings(settings: new, streaming: false)
        let data = try JSONEncoder().encode(StoredSettings(new))
        try secrets.save(new.pairingKey)
        values.set(data, forKey: Self.key)
        settings = new
    }

    private static func describe(_ error: Error) -> String {
        error is DecodingError ? "unreadable: \(error)" : userText(error)
    }
}

/// `AppSettings` without the pairing key, in a Codable form: what the key-value store keeps
/// and what a recording's header says about the settings it was made with.
public struct StoredSettings: Codable, Equatable {
    public var camera: String
    public var resolution: String
    public var fps: UInt32
    public var focus: String
    public var lensPosition: Float
    public var exposureLocked: Bool
    /// Optional so that settings stored before they existed still load (with the defaults).
    public var maxExposureS: Double?
    public var calibratedReadoutS: Double?
    public var bgra: Bool
    public var decimate: Float
    public var quadSigma: Float
    public var maxHamming: UInt32
    public var threads: UInt32
    public var linearEdges: Bool
    public var regionSearch: Bool
    public var smooth: Bool
    /// Optional so that settings stored before the dense refinement existed still load (off).
    public var dense: Bool?
    public var receiverHost: String
    public var receiverPort: UInt32
    public var recordVideo: Bool

    public init(_ settings: AppSettings) {
        camera = Self.cameraNames[settings.camera] ?? "back_wide"
        resolution = Self.resolutionNames[settings.resolution] ?? "1080p"
        fps = settings.fps
        focus = Self.focusNames[settings.focus] ?? "planned"
        lensPosition = settings.lensPosition
        exposureLocked = settings.exposureLocked
        maxExposureS = settings.maxExposureS
        calibratedReadoutS = settings.calibratedReadoutS
        bgra = settings.bgra
        decimate = settings.tracker.decimate
        quadSigma = settings.tracker.quadSigma
        maxHamming = settings.tracker.maxHamming
        threads = settings.tracker.threads
        linearEdges = settings.tracker.linearEdges
        regionSearch = settings.tracker.regionSearch
        smooth = settings.tracker.smooth
        dense = settings.tracker.dense
        receiverHost = settings.receiverHost
        receiverPort = settings.receiverPort
        recordVideo = settings.recordVideo
    }

    /// These values over `base` (whose pairing key is kept); an unknown name is refused. The
    /// tracker's readout is not kept: it comes from the camera each time it is configured.
    public func applied(to base: AppSettings) throws -> AppSettings {
        guard let camera = Self.cameraNames.first(where: { $0.value == camera })?.key else {
            throw AppError(message: "unknown camera \"\(camera)\"")
        }
        guard let resolution = Self.resolutionNames.first(where: { $0.value == resolution })?.key else {
            throw AppError(message: "unknown resolution \"\(resolution)\"")
        }
        guard let focus = Self.focusNames.first(where: { $0.value == focus })?.key else {
            throw AppError(message: "unknown focus mode \"\(focus)\"")
        }
        let tracker = JawTrackCore.Settings(
            decimate: decimate, quadSigma: quadSigma, maxHamming: maxHamming, threads: threads,
            linearEdges: linearEdges, regionSearch: regionSearch, smooth: smooth, readoutS: 0,
            dense: dense ?? false
        )
        return AppSettings(
            camera: camera, resolution: resolution, fps: fps, focus: focus, lensPosition: lensPosition,
            exposureLocked: exposureLocked, maxExposureS: maxExposureS ?? defaultAppSettings().maxExposureS,
            calibratedReadoutS: calibratedReadoutS, bgra: bgra, tracker: tracker, receiverHost: receiverHost,
            receiverPort: receiverPort, pairingKey: base.pairingKey, recordVideo: recordVideo
        )
    }

    /// As JSON with snake_case keys and sorted, for a recording's header.
    public func headerJSON() -> String? {
        let encoder = JSONEncoder()
        encoder.keyEncodingStrategy = .convertToSnakeCase
        encoder.outputFormatting = [.sortedKeys]
        guard let data = try? encoder.encode(self) else {
            return nil
        }
        return String(decoding: data, as: UTF8.self)
    }

    static let cameraNames: [Camera: String] = [.backWide: "back_wide", .backTele: "back_tele", .front: "front"]
    static let resolutionNames: [Resolution: String] = [.hd720: "720p", .hd1080: "1080p", .uhd4k: "4k"]
    /// "auto" and "manual" as stored before the capture plan, which added "planned".
    static let focusNames: [FocusMode: String] = [.planned: "planned", .auto: "auto", .manual: "manual"]
}
