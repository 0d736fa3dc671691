import Foundation
import JawTrackCore
import JawTrackKit
import XCTest

/// Settings kept, reloaded and validated by the library; the settings screen's logic.
final class SettingsTests: XCTestCase {
    private let key = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f"

    func testSavedSettingsReloadAndTheKeyStaysInTheSecretStore() throws {
        let values = MemoryKeyValueStore()
        let secrets = MemorySecretStore()
        let store = SettingsStore(values: values, secrets: secrets)
        XCTAssertNil(store.loadProblem)
        XCTAssertEqual(store.settings, defaultAppSettings())
        var changed = store.settings
        changed.camera = .backTele
        changed.resolution = .uhd4k
        changed.fps = 60
        changed.focus = .manual
        changed.lensPosition = 0.25
        changed.tracker.decimate = 1.5
        changed.tracker.smooth = true
        changed.tracker.dense = true
        changed.receiverHost = "10.0.0.2"
        changed.receiverPort = 5005
        changed.pairingKey = key
        try store.save(changed)
        XCTAssertEqual(secrets.secret, key)
        let stored = String(decoding: try XCTUnwrap(values.data(forKey: SettingsStore.key)), as: UTF8.self)
        XCTAssertFalse(stored.contains(key), "the pairing key never goes to the key-value store")
        let reloaded = SettingsStore(values: values, secrets: secrets)
        XCTAssertNil(reloaded.loadProblem)
        XCTAssertEqual(reloaded.settings, changed)
    }

    func testSettingsStoredBeforeTheDenseRefinementLoadWithItOff() throws {
        let values = MemoryKeyValueStore()
        let store = SettingsStore(values: values, secrets: MemorySecretStore())
        var on = store.settings
        on.tracker.dense = true
        try store.save(on)
        var stored = try XCTUnwrap(
            JSONSerialization.jsonObject(with: try XCTUnwrap(values.data(forKey: SettingsStore.key))) as? [String: Any])
        XCTAssertEqual(stored["dense"] as? Bool, true)
        stored.removeValue(forKey: "dense")
        values.set(try JSONSerialization.data(withJSONObject: stored), forKey: SettingsStore.key)
        let older = SettingsStore(values: values, secrets: MemorySecretStore())
        XCTAssertNil(older.loadProblem)
        XCTAssertFalse(older.settings.tracker.dense)
    }

    func testAFreshInstallRunsADetectorThreadPerPerformanceCoreAndSavedSettingsWin() throws {
        let values = MemoryKeyValueStore()
        let twoCores = SettingsStore(values: values, secrets: MemorySecretStore(), performanceCores: 2)
        XCTAssertEqual(twoCores.settings.tracker.threads, 2)
        XCTAssertEqual(SettingsStore(values: values, secrets: MemorySecretStore()).settings.tracker.threads, 1,
                       "unknown cores: one thread")
        var one = twoCores.settings
        one.tracker.threads = 1
        try twoCores.save(one)
        let reloaded = SettingsStore(values: values, secrets: MemorySecretStore(), performanceCores: 2)
        XCTAssertEqual(reloaded.settings.tracker.threads, 1, "the user's saved choice stands")
    }

    func testThePlannedFocusModeRoundTripsAndSettingsStoredBeforeItStillLoad() throws {
        let values = MemoryKeyValueStore()
        let store = SettingsStore(values: values, secrets: MemorySecretStore())
        var planned = store.settings
        planned.focus = .planned
        planned.fps = 30
        try store.save(planned)
        let stored = try JSONSerialization.jsonObject(with: try XCTUnwrap(values.data(forKey: SettingsStore.key))) as? [String: Any]
        XCTAssertEqual(stored?["focus"] as? String, "planned")
        XCTAssertEqual(SettingsStore(values: values, secrets: MemorySecretStore()).settings, planned)

        for (name, mode) in [("auto", FocusMode.auto), ("manual", .manual)] {
            var old = try XCTUnwrap(stored)
            old["focus"] = name
            values.set(try JSONSerialization.data(withJSONObject: old), forKey: SettingsStore.key)
            let loaded = SettingsStore(values: values, secrets: MemorySecretStore())
            XCTAssertNil(loaded.loadProblem)
            XCTAssertEqual(loaded.settings.focus, mode, "stored before the planned mode existed")
            XCTAssertEqual(StoredSettings(loaded.settings).focus, name)
        }
        var unknown = try XCTUnwrap(stored)
        unknown["focus"] = "macro"
        values.set(try JSONSerialization.data(withJSONObject: unknown), forKey: SettingsStore.key)
        XCTAssertTrue(try XCTUnwrap(SettingsStore(values: values, secrets: MemorySecretStore()).loadProblem).contains("macro"))
    }

    func testTheLibraryRefusesBadSettingsAndNothingIsSaved() throws {
        let values = MemoryKeyValueStore()
        let store = SettingsStore(values: values, secrets: MemorySecretStore())
        var bad = store.settings
        bad.tracker.threads = 0
        XCTAssertThrowsError(try store.save(bad)) { error in
            guard case JawTrackError.InvalidSetting(let setting, let message) = error else {
                return XCTFail("expected InvalidSetting, got \(error)")
            }
            XCTAssertEqual(setting, "threads")
            XCTAssertEqual(userText(error), message)
        }
        XCTAssertNil(values.data(forKey: SettingsStore.key))
        XCTAssertEqual(store.settings, defaultAppSettings())
    }

    func testUnreadableOrInvalidStoredSettingsFallBackToTheDefaultsAndSaySo() throws {
        let values = MemoryKeyValueStore()
        values.set(Data("{not json".utf8), forKey: SettingsStore.key)
        let garbled = SettingsStore(values: values, secrets: MemorySecretStore())
        XCTAssertEqual(garbled.settings, defaultAppSettings())
        XCTAssertTrue(try XCTUnwrap(garbled.loadProblem).contains("defaults are"))

        var stored = StoredSettings(defaultAppSettings())
        stored.decimate = 7
        values.set(try JSONEncoder().encode(stored), forKey: SettingsStore.key)
        let invalid = SettingsStore(values: values, secrets: MemorySecretStore())
        XCTAssertEqual(invalid.settings, defaultAppSettings())
        XCTAssertTrue(try XCTUnwrap(invalid.loadProblem).contains("decimation"), "the library's reason")

        stored = StoredSettings(defaultAppSettings())
        stored.camera = "periscope"
        values.set(try JSONEncoder().encode(stored), forKey: SettingsStore.key)
        XCTAssertTrue(try XCTUnwrap(SettingsStore(values: values, secrets: MemorySecretStore()).loadProblem).contains("periscope"))
    }

    func testALockedSecretStoreIsReported() {
        let secrets = MemorySecretStore()
        secrets.failure = "User interaction is not allowed."
        let store = SettingsStore(values: MemoryKeyValueStore(), secrets: secrets)
        XCTAssertEqual(store.loadProblem, "Keychain: User interaction is not allowed.")
        XCTAssertThrowsError(try store.save(defaultAppSettings()))
    }

    func testTheHeaderJsonUsesSnakeCaseAndHoldsNoKey() throws {
        var settings = defaultAppSettings()
        settings.pairingKey = key
        let json = try XCTUnwrap(StoredSettings(settings).headerJSON())
        XCTAssertTrue(json.contains("\"receiver_port\""))
        XCTAssertTrue(json.contains("\"quad_sigma\""))
        XCTAssertFalse(json.contains(key))
    }

    func testTheFormValidatesThroughTheLibrary() {
        var form = SettingsForm(defaultAppSettings())
        XCTAssertNil(form.problem)
        XCTAssertNotNil(form.streamingProblem, "no receiver or key yet")
        form.draft.tracker.quadSigma = 2
        XCTAssertTrue(form.problem?.lowercased().contains("sigma") ?? false, form.problem ?? "")
        form.draft.tracker.quadSigma = 0
        form.portText = "50a05"
        XCTAssertEqual(form.draft.receiverPort, 5005)
        XCTAssertEqual(form.portText, "5005")
        form.portText = ""
        XCTAssertEqual(form.draft.receiverPort, 0)
        XCTAssertFalse(form.showsLensPosition)
        XCTAssertEqual(SettingsForm.focusModes.map(\.label), ["Planned", "Auto", "Manual"])
        XCTAssertEqual(form.draft.focus, SettingsForm.focusModes[0].value, "the default is shown first")
        XCTAssertFalse(form.usesResolution, "the plan chooses the format")
        XCTAssertTrue(try XCTUnwrap(form.focusNote).contains("resolution setting is not used"))
        form.draft.focus = .manual
        XCTAssertTrue(form.showsLensPosition)
        XCTAssertTrue(form.usesResolution)
        XCTAssertNil(form.focusNote)
        XCTAssertEqual(SettingsForm.decimations.map(\.label), ["1", "1.5", "2", "3", "4"])
        XCTAssertEqual(SettingsForm.cameras.count, 3)
    }

    func testAScannedPairingCodeFillsTheReceiver() throws {
        var form = SettingsForm(defaultAppSettings())
        form.scanned("jawtrack://pair?host=192.168.1.20&port=5005&key=\(key)")
        XCTAssertEqual(form.draft.receiverHost, "192.168.1.20")
        XCTAssertEqual(form.draft.receiverPort, 5005)
        XCTAssertEqual(form.draft.pairingKey, key)
        XCTAssertEqual(form.keyId, "aac4ef0c730c0623")
        XCTAssertEqual(form.pairingNote, "Paired: key id aac4ef0c730c0623.")
        XCTAssertNil(form.streamingProblem)
        try validateAppSettings(settings: form.draft, streaming: true)

        form.scanned("https://example.com")
        XCTAssertTrue(try XCTUnwrap(form.pairingNote).hasPrefix("Not a JawTrack pairing code: "))
        XCTAssertEqual(form.draft.pairingKey, key, "a bad code changes nothing")
        form.draft.pairingKey = "abc"
        XCTAssertNil(form.keyId)
        XCTAssertThrowsError(try pairingKeyId(text: "abc"))
        form.scanFailed("The camera is not available.")
        XCTAssertEqual(form.pairingNote, "The camera is not available.")
    }
}
