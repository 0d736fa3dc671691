#!/usr/bin/env bash
# Builds the Rust library for the iPhone (device, and the simulator on Apple-silicon Macs),
# generates its Swift bindings and packs both into the JawTrackKit Swift package:
#   ios/JawTrackKit/JawTrackFFI.xcframework               static libraries + C headers + module map
#   ios/JawTrackKit/Sources/JawTrackCore/jawtrack.swift   uniffi's Swift bindings (target JawTrackCore)
# Needs a Mac with Xcode and rustup. Runs from the repository root, ios/ or anywhere else.
set -euo pipefail

ios_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$ios_dir/.." && pwd)"
cd "$repo"

for tool in rustup cargo xcodebuild; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "build-rust.sh: '$tool' not found; this runs on a Mac with Xcode and rustup" >&2
    exit 1
  fi
done

target_dir="${CARGO_TARGET_DIR:-$repo/target}"
package_dir="$ios_dir/JawTrackKit"
generated="$target_dir/ios/bindings"
headers="$target_dir/ios/headers"
xcframework="$package_dir/JawTrackFFI.xcframework"
device_lib="$target_dir/aarch64-apple-ios/release/libjawtrack_ffi.a"
simulator_lib="$target_dir/aarch64-apple-ios-sim/release/libjawtrack_ffi.a"
bindgen="$target_dir/release/uniffi-bindgen"

# The same minimum iOS as the app, so the linker does not warn about newer object files.
export IPHONEOS_DEPLOYMENT_TARGET=16.0

echo "== Rust targets"
rustup target add aarch64-apple-ios aarch64-apple-ios-sim

echo "== libjawtrack_ffi for the device and the simulator"
cargo build --release -p jawtrack-ffi --lib --target aarch64-apple-ios
cargo build --release -p jawtrack-ffi --lib --target aarch64-apple-ios-sim

echo "== uniffi-bindgen (host)"
cargo build --release -p uniffi-bindgen

echo "== Swift bindings"
rm -rf "$generated" "$headers"
mkdir -p "$generated" "$headers"
# uniffi reads the interface from the library's metadata; it reads static archives too. Should
# that fail, the host's dynamic library carries the same metadata.
if ! "$bindgen" generate --library "$device_lib" --language swift --out-dir "$generated"; then
  echo "build-rust.sh: generating from the iOS archive failed; using the host library" >&2
  cargo build --release -p jawtrack-ffi --lib
  "$bindgen" generate --library "$target_dir/release/libjawtrack_ffi.dylib" --language swift --out-dir "$generated"
fi
for file in jawtrack.swift jawtrackFFI.h; do
  if [[ ! -f "$generated/$file" ]]; then
    echo "build-rust.sh: uniffi-bindgen did not write $file" >&2
    exit 1
  fi
done

echo "== Headers and module map (jawtrackFFI: uniffi's scaffolding; JawTrackC: the frame entry points)"
cp "$generated/jawtrackFFI.h" "$headers/"
cp "$repo/crates/ffi/include/jawtrack.h" "$headers/"
cat > "$headers/module.modulemap" <<'MODULEMAP'
module jawtrackFFI {
    header "jawtrackFFI.h"
    export *
}

module JawTrackC {
    header "jawtrack.h"
    export *
}
MODULEMAP

echo "== XCFramework"
rm -rf "$xcframework"
xcodebuild -create-xcframework \
  -library "$device_lib" -headers "$headers" \
  -library "$simulator_lib" -headers "$headers" \
  -output "$xcframework"

mkdir -p "$package_dir/Sources/JawTrackCore"
cp "$generated/jawtrack.swift" "$package_dir/Sources/JawTrackCore/jawtrack.swift"

echo "Done: $xcframework"
echo "      $package_dir/Sources/JawTrackCore/jawtrack.swift"
echo "Next: cd ios && xcodegen generate && open JawTrack.xcodeproj"
