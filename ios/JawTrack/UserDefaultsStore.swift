// Adapts UserDefaults to JawTrackKit's KeyValueStore: the settings' data under the kit's key.
import Foundation
import JawTrackKit

final class UserDefaultsStore: KeyValueStore {
    func data(forKey key: String) -> Data? { UserDefaults.standard.data(forKey: key) }

    func set(_ data: Data, forKey key: String) { UserDefaults.standard.set(data, forKey: key) }
}
