// Adapts the Keychain (a Security generic password, this device only) to JawTrackKit's
// SecretStore: the pairing key, out of UserDefaults and backups in clear.
import Foundation
import JawTrackKit
import Security

final class KeychainStore: SecretStore {
    private let query: [String: Any] = [
        kSecClass as String: kSecClassGenericPassword,
        kSecAttrService as String: "org.jawtrack.app.pairing",
        kSecAttrAccount as String: "pairing-key",
    ]

    func load() throws -> String {
        var search = query
        search[kSecReturnData as String] = true
        search[kSecMatchLimit as String] = kSecMatchLimitOne
        var item: CFTypeRef?
        let status = SecItemCopyMatching(search as CFDictionary, &item)
        guard status != errSecItemNotFound else { return "" }
        try check(status)
        return (item as? Data).map { String(decoding: $0, as: UTF8.self) } ?? ""
    }

    func save(_ key: String) throws {
        let deleted = SecItemDelete(query as CFDictionary)
        if deleted != errSecItemNotFound { try check(deleted) }
        guard !key.isEmpty else { return }
        var item = query
        item[kSecValueData as String] = Data(key.utf8)
        item[kSecAttrAccessible as String] = kSecAttrAccessibleAfterFirstUnlockThisDeviceOnly
        try check(SecItemAdd(item as CFDictionary, nil))
    }

    private func check(_ status: OSStatus) throws {
        guard status != errSecSuccess else { return }
        throw PlatformText.keychain(status: status, text: SecCopyErrorMessageString(status, nil) as String?)
    }
}
