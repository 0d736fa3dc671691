#!/usr/bin/env bash
# Swift on Linux for the iPhone app's JawTrackKit: Debian trixie's `swiftlang` (6.0.3) in a
# `debootstrap --variant=minbase` root under target/, with the repository bind-mounted at /repo.
# The machine's own Debian has no Swift; Apple's frameworks exist nowhere but on a Mac, which is
# why every decision of the app lives in JawTrackKit (no Apple-only import) and is tested here.
#
#   bash ios/swift-on-linux.sh setup        make the root, or check and reuse it (seconds)
#   bash ios/swift-on-linux.sh run CMD...   run CMD inside the root, in /repo
#   bash ios/swift-on-linux.sh test         build the Rust library, generate and compile the
#                                           uniffi bindings, prepare the fixtures, then
#                                           `swift build` and `swift test` of JawTrackKit, and
#                                           check that the tests ran every library call it makes
#   bash ios/swift-on-linux.sh lines        the app's hand-written Swift: JawTrackKit vs the Apple layer
#   bash ios/swift-on-linux.sh remove       unmount anything left inside the root, then delete it
#
# Needs root (debootstrap, chroot, mount) and the network the first time (about 3 minutes and
# 3.3 GB). JAWTRACK_SWIFT_ROOT overrides where the root lives. Every failure names its step.
set -euo pipefail

ios_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$ios_dir/.." && pwd)"
root="${JAWTRACK_SWIFT_ROOT:-$repo/target/swift-root}"
kit="$ios_dir/JawTrackKit"
work="$repo/target/swift"
step="starting"
mounted=()

reported=no
fail() {
  echo "swift-on-linux: FAILED at step '$step': $*" >&2
  reported=yes
  exit 1
}
trap 'status=$?; if [ $status -ne 0 ] && [ "$step" != done ] && [ $reported = no ]; then echo "swift-on-linux: FAILED at step '"'"'$step'"'"' (exit $status)" >&2; fi; unmount_all' EXIT

unmount_all() {
  local i
  for ((i = ${#mounted[@]} - 1; i >= 0; i--)); do
    umount "${mounted[$i]}" 2>/dev/null || umount -l "${mounted[$i]}" 2>/dev/null || true
  done
  mounted=()
}

lines_split() {
  step="counting lines"
  # Code lines: not blank, not only a comment. Generated bindings and tests are counted apart.
  count() { awk '!/^[[:space:]]*$/ && !/^[[:space:]]*\/\// {n++} END {print n+0}' "$@" /dev/null; }
  mapfile -t kit_files < <(find "$kit/Sources/JawTrackKit" -name '*.swift' | sort)
  mapfile -t apple_files < <(find "$ios_dir/JawTrack" -name '*.swift' | sort)
  mapfile -t test_files < <(find "$kit/Tests" -name '*.swift' | sort)
  local k a t
  k=$(count "${kit_files[@]}")
  a=$(count "${apple_files[@]}")
  t=$(count "${test_files[@]}")
  echo "app Swift (code lines, no blanks or comment lines; generated bindings excluded):"
  echo "  JawTrackKit (compiled and tested on Linux): $k lines in ${#kit_files[@]} files"
  echo "  Apple layer (ios/JawTrack, compiled by Xcode only): $a lines in ${#apple_files[@]} files"
  awk -v k="$k" -v a="$a" 'BEGIN {printf "  JawTrackKit share: %.1f %%\n", 100 * k / (k + a)}'
  echo "  tests (ios/JawTrackKit/Tests): $t lines"
}

if [ "${1:-}" = lines ]; then
  lines_split
  step=done
  exit 0
fi

[ "$(id -u)" -eq 0 ] || fail "needs root (debootstrap, chroot and mount); run it with sudo"

if [ "${1:-}" = remove ]; then
  step="removing the root $root"
  # Never delete through a mount: a bind of the repository inside would take the sources with it.
  for dir in "$root/repo/target/swift" "$root/repo" "$root/proc"; do
    if mountpoint -q "$dir"; then
      umount "$dir" || umount -l "$dir" || fail "cannot unmount $dir; not deleting"
    fi
  done
  if grep -q " $root/" /proc/mounts; then
    fail "something is still mounted under $root; not deleting"
  fi
  rm -rf "$root" "$root.partial"
  step=done
  exit 0
fi

setup() {
  if [ -f "$root/.jawtrack-ready" ]; then
    return
  fi
  step="installing debootstrap on the host"
  if ! command -v debootstrap >/dev/null 2>&1; then
    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq debootstrap >/dev/null) \
      || fail "apt-get install debootstrap failed"
  fi
  step="debootstrap --variant=minbase trixie into $root"
  echo "== making the Debian trixie root for Swift (once; about a minute and 3.3 GB): $root"
  rm -rf "$root.partial"
  mkdir -p "$(dirname "$root")"
  debootstrap --variant=minbase trixie "$root.partial" http://deb.debian.org/debian >"$work-debootstrap.log" 2>&1 \
    || fail "debootstrap failed; its log: $work-debootstrap.log"
  rm -rf "$root"
  mv "$root.partial" "$root"
  step="installing swiftlang in the root"
  cp /etc/resolv.conf "$root/etc/resolv.conf"
  mount_inside
  chroot "$root" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin DEBIAN_FRONTEND=noninteractive \
    sh -c 'apt-get update -qq && apt-get install -y -qq --no-install-recommends swiftlang libc6-dev >/dev/null && apt-get clean' \
    || fail "apt-get install swiftlang inside the root failed"
  touch "$root/.jawtrack-ready"
}

mount_inside() {
  step="mounting /proc and the repository inside the root"
  mkdir -p "$root/proc" "$root/repo"
  if ! mountpoint -q "$root/proc"; then
    mount -t proc proc "$root/proc" || fail "mount -t proc failed (swift needs /proc/self/exe)"
    mounted+=("$root/proc")
  fi
  # The repository read-only, only target/swift (builds, fixtures, test output) writable: the
  # root lives under target/, so were a mount ever left behind (a killed run), `cargo clean` or
  # `rm -rf target` would reach the sources through it; read-only, they stay.
  if ! mountpoint -q "$root/repo"; then
    mount --bind "$repo" "$root/repo" || fail "mount --bind of the repository failed"
    mounted+=("$root/repo")
    mount -o remount,bind,ro "$root/repo" || fail "remounting the repository read-only failed"
  fi
  if ! mountpoint -q "$root/repo/target/swift"; then
    mount --bind "$work" "$root/repo/target/swift" || fail "mount --bind of target/swift failed"
    mounted+=("$root/repo/target/swift")
  fi
}

inside() {
  chroot "$root" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin HOME=/root LANG=C.UTF-8 \
    JAWTRACK_SWIFT_FIXTURES=/repo/target/swift/fixtures JAWTRACK_SWIFT_OUT=/repo/target/swift/out \
    sh -c 'cd /repo && "$@"' sh "$@"
}

mkdir -p "$work"
setup
mount_inside
step="checking swift inside the root"
inside swift --version >/dev/null 2>&1 || fail "swift does not run inside $root (remove it to rebuild it)"

case "${1:-}" in
  setup)
    inside swift --version
    ;;
  run)
    shift
    [ $# -gt 0 ] || fail "run needs a command"
    step="running $*"
    inside "$@"
    ;;
  test)
    export CARGO_TARGET_DIR="$repo/target"
    step="building libjawtrack_ffi, uniffi-bindgen and jawtrack (release)"
    (cd "$repo" && cargo build --release -q -p jawtrack-ffi --lib && cargo build --release -q -p uniffi-bindgen \
      && cargo build --release -q -p jawtrack-cli) || fail "cargo build failed"
    step="generating the Swift bindings"
    rm -rf "$work/bindings"
    "$repo/target/release/uniffi-bindgen" generate --library "$repo/target/release/libjawtrack_ffi.so" \
      --language swift --out-dir "$work/bindings" >/dev/null || fail "uniffi-bindgen failed"
    mkdir -p "$kit/Sources/JawTrackCore" "$kit/Linux/jawtrackFFI"
    cp "$work/bindings/jawtrack.swift" "$kit/Sources/JawTrackCore/jawtrack.swift"
    cp "$work/bindings/jawtrackFFI.h" "$kit/Linux/jawtrackFFI/jawtrackFFI.h"
    step="preparing the fixtures (raw luma frames and the poses jawtrack track gets)"
    rm -rf "$work/fixtures" "$work/out"
    mkdir -p "$work/fixtures" "$work/out"
    # static-1080p for the pipeline and the screen; hinge-1080p (the lower jaw turning) for the
    # marker calibration, whose views must come from different angles.
    for set in static-1080p hinge-1080p; do
      intrinsics=$(python3 -c 'import json,sys; i=json.load(open(sys.argv[1]))["intrinsics"]; print(",".join(repr(float(i[k])) for k in ("fx","fy","cx","cy","k1","k2")))' \
        "$repo/fixtures/$set/ground_truth.json") || fail "reading fixtures/$set/ground_truth.json"
      (cd "$repo" && cargo run --release -q -p jawtrack-test-support --example luma-pgm -- "fixtures/$set" "$work/fixtures/$set") \
        || fail "converting fixtures/$set to PGM"
      echo "$intrinsics" >"$work/fixtures/$set/intrinsics.txt"
      # Tracked inside the root, beside the Swift tests: glibc's libm differs between Debian
      # releases in the last bits of sin/cos, which the pose solver's iterations amplify to 1e-6 mm.
      # At the 2 ms exposure the tests give each frame (Support.swift's `play`): the exposure
      # says how far tags smear, and so which way a frame's tags are looked for.
      inside target/release/jawtrack track "fixtures/$set" --intrinsics "$intrinsics" --exposure-ms 2 \
        --out "target/swift/fixtures/$set/track.jsonl" >/dev/null 2>&1 || fail "jawtrack track fixtures/$set"
    done
    cp "$repo/fixtures/wire/golden.json" "$work/fixtures/wire-golden.json"
    "$repo/target/release/jawtrack" marker --out "$work/fixtures/marker.json" >/dev/null || fail "jawtrack marker"
    linker=(-Xlinker -L/repo/target/release -Xlinker -rpath -Xlinker /repo/target/release)
    step="swift build (JawTrackKit and the uniffi bindings)"
    inside swift build --package-path ios/JawTrackKit --scratch-path /repo/target/swift/build "${linker[@]}" \
      || fail "swift build failed"
    step="swift test (JawTrackKit's XCTest cases against the real library)"
    inside swift test --enable-code-coverage --package-path ios/JawTrackKit --scratch-path /repo/target/swift/build \
      "${linker[@]}" || fail "swift test failed"
    step="checking that the Swift tests run every call JawTrackKit makes into the library"
    inside /usr/libexec/swift/bin/llvm-cov show target/swift/build/debug/JawTrackKitPackageTests.xctest \
      -instr-profile=target/swift/build/debug/codecov/default.profdata ios/JawTrackKit/Sources/JawTrackKit \
      >"$work/coverage.txt" || fail "llvm-cov show failed"
    python3 "$ios_dir/check-library-calls.py" "$work/bindings/jawtrack.swift" "$repo/crates/ffi/include/jawtrack.h" \
      "$work/coverage.txt" || fail "a library call of JawTrackKit is never run by the tests"
    lines_split
    ;;
  *)
    fail "usage: bash ios/swift-on-linux.sh setup | run CMD... | test | lines | remove"
    ;;
esac
step=done
