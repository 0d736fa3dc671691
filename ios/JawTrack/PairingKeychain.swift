import Foundation
import Security

/// The pairing key in the Keychain, on this device only: it seals the stream, so it stays out of
/// UserDefaults, backups in clear and the recordings (which carry only its id).
enum PairingKeychain {
    private static let service = "org.jawtrack.app.pairing"
    private static let account = "pairing-key"

    private static var query: [String: Any] {
        [
            kSecClass as String: kSecClassGenericPassword,
            kSecAttrService as String: service,
            kSecAttrAccount as String: account,
        ]
    }

    /// The stored key, or "" when none is.
    static func load() throws -> String {
        var search = query
        search[kSecReturnData as String] = true
        search[kSecMatchLimit as String] = kSecMatchLimitOne
        var item: CFTypeRef?
        let status = SecItemCopyMatching(search as CFDictionary, &item)
        if status == errSecItemNotFound {
            return ""
        }
        guard status == errSecSuccess else {
            throw keychainError(status)
        }
        guard let data = item as? Data else {
            return ""
        }
        return String(decoding: data, as: UTF8.self)
    }

    /// Replaces the stored key; an empty key removes it.
    static func save(_ key: String) throws {
        let deleted = SecItemDelete(query as CFDictionary)
        guard deleted == errSecSuccess || deleted == errSecItemNotFound else {
            throw keychainError(deleted)
        }
        if key.isEmpty {
            return
        }
        var item = query
        item[kSecValueData as String] = Data(key.utf8)
        item[kSecAttrAccessible as String] = kSecAttrAccessibleAfterFirstUnlockThisDeviceOnly
        let added = SecItemAdd(item as CFDictionary, nil)
        guard added == errSecSuccess else {
            throw keychainError(added)
        }
    }

    private static func keychainError(_ status: OSStatus) -> AppError {
        let text = (SecCopyErrorMessageString(status, nil) as String?) ?? "error \(status)"
        return AppError(message: "Keychain: \(text)")
    }
}
