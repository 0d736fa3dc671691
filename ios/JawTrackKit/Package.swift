// swift-tools-version:5.9
// JawTrackKit: every decision the iPhone app makes, in Swift with no Apple-only import, so it
// compiles and is tested on Linux too (`bash ios/swift-on-linux.sh test`). Three targets:
//   JawTrackCore  the uniffi-generated bindings of the Rust library (jawtrack.swift, generated)
//   JawTrackKit   the app's frame pipeline, settings, recording, link, screen model, overlay
//   the library   on a Mac: JawTrackFFI.xcframework (`bash ios/build-rust.sh`); on Linux: the
//                 host-built libjawtrack_ffi.so through two system-library modules, its folder
//                 given to the linker by swift-on-linux.sh.
import PackageDescription

#if os(Linux)
let libraryTargets: [Target] = [
    .systemLibrary(name: "jawtrackFFI", path: "Linux/jawtrackFFI"),
    .systemLibrary(name: "JawTrackC", path: "Linux/JawTrackC"),
]
let coreDependencies: [Target.Dependency] = ["jawtrackFFI"]
let kitDependencies: [Target.Dependency] = ["JawTrackCore", "JawTrackC"]
#else
let libraryTargets: [Target] = [
    .binaryTarget(name: "JawTrackFFI", path: "JawTrackFFI.xcframework"),
]
let coreDependencies: [Target.Dependency] = ["JawTrackFFI"]
let kitDependencies: [Target.Dependency] = ["JawTrackCore", "JawTrackFFI"]
#endif

let package = Package(
    name: "JawTrackKit",
    platforms: [.iOS(.v16), .macOS(.v13)],
    products: [
        .library(name: "JawTrackKit", targets: ["JawTrackKit", "JawTrackCore"]),
    ],
    targets: libraryTargets + [
        .target(name: "JawTrackCore", dependencies: coreDependencies, path: "Sources/JawTrackCore"),
        .target(name: "JawTrackKit", dependencies: kitDependencies, path: "Sources/JawTrackKit"),
        .testTarget(name: "JawTrackKitTests", dependencies: ["JawTrackKit"], path: "Tests/JawTrackKitTests"),
    ]
)
