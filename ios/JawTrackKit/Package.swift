// swift-tools-version:5.9
// The Rust library as a Swift package: the static libraries (device and simulator) with their C
// headers in an XCFramework, the uniffi-generated bindings and the zero-copy frame path.
// `bash ios/build-rust.sh` makes JawTrackFFI.xcframework and Sources/JawTrackCore/jawtrack.swift.
import PackageDescription

let package = Package(
    name: "JawTrackCore",
    platforms: [.iOS(.v16)],
    products: [
        .library(name: "JawTrackCore", targets: ["JawTrackCore"]),
    ],
    targets: [
        .binaryTarget(name: "JawTrackFFI", path: "JawTrackFFI.xcframework"),
        .target(
            name: "JawTrackCore",
            dependencies: ["JawTrackFFI"],
            path: "Sources/JawTrackCore"
        ),
    ]
)
