import Foundation
import JawTrackCore
import JawTrackKit
import XCTest

/// Where `ios/swift-on-linux.sh test` put the prepared fixtures (raw luma frames, the poses
/// `jawtrack track` got for them, the golden datagrams) and where tests leave files for the
/// Rust side to read. The tests run only through that script.
enum Fixtures {
    static func directory() throws -> URL {
        guard let path = ProcessInfo.processInfo.environment["JAWTRACK_SWIFT_FIXTURES"] else {
            throw AppError(message: "JAWTRACK_SWIFT_FIXTURES is not set: run the tests with `bash ios/swift-on-linux.sh test`")
        }
        return URL(fileURLWithPath: path)
    }

    static func output() throws -> URL {
        guard let path = ProcessInfo.processInfo.environment["JAWTRACK_SWIFT_OUT"] else {
            throw AppError(message: "JAWTRACK_SWIFT_OUT is not set: run the tests with `bash ios/swift-on-linux.sh test`")
        }
        let url = URL(fileURLWithPath: path)
        try FileManager.default.createDirectory(at: url, withIntermediateDirectories: true)
        return url
    }

    /// A fresh, empty folder for one test.
    static func scratch(_ name: String) throws -> URL {
        let url = try output().appendingPathComponent("scratch").appendingPathComponent(name)
        try? FileManager.default.removeItem(at: url)
        try FileManager.default.createDirectory(at: url, withIntermediateDirectories: true)
        return url
    }
}

/// An 8-bit grayscale frame read from a binary PGM (P5).
struct LumaImage {
    let width: Int
    let height: Int
    let pixels: [UInt8]

    init(pgm url: URL) throws {
        let data = try Data(contentsOf: url)
        var fields: [String] = []
        var index = data.startIndex
        while fields.count < 4 {
            while index < data.endIndex, data[index] == 0x20 || data[index] == 0x0A || data[index] == 0x0D || data[index] == 0x09 {
                index += 1
            }
            var field = ""
            while index < data.endIndex, ![0x20, 0x0A, 0x0D, 0x09].contains(data[index]) {
                field.append(Character(UnicodeScalar(data[index])))
                index += 1
            }
            fields.append(field)
        }
        index += 1
        guard fields[0] == "P5", let width = Int(fields[1]), let height = Int(fields[2]), fields[3] == "255",
              data.endIndex - index == width * height
        else {
            throw AppError(message: "\(url.path): not an 8-bit binary PGM (header \(fields))")
        }
        self.width = width
        self.height = height
        pixels = [UInt8](data[index...])
    }

    /// The frame as a camera would hand it over: rows `padding` bytes longer than the pixels
    /// (filled with a pattern the detector must never read), as `layout`.
    func padded(_ layout: PixelLayout, padding: Int = 64) -> (bytes: [UInt8], bytesPerRow: Int) {
        let rowBytes = width * layout.bytesPerPixel
        let bytesPerRow = rowBytes + padding
        var bytes = [UInt8](repeating: 0xA5, count: bytesPerRow * height)
        for row in 0..<height {
            for column in 0..<width {
                let y = pixels[row * width + column]
                let at = row * bytesPerRow + column * layout.bytesPerPixel
                switch layout {
                case .luma:
                    bytes[at] = y
                case .bgra:
                    bytes[at] = y
                    bytes[at + 1] = y
                    bytes[at + 2] = y
                    bytes[at + 3] = 255
                }
            }
        }
        return (bytes, bytesPerRow)
    }
}

/// The fixture set `static-1080p` as frames: its PGMs, its intrinsics and the lines `jawtrack
/// track` wrote for it.
struct FixtureSet {
    let frames: [LumaImage]
    /// fx, fy, cx, cy, k1, k2.
    let intrinsics: [Double]
    /// `jawtrack track`'s frame lines (header dropped), as JSON objects.
    let tracked: [[String: Any]]

    static func load(_ name: String = "static-1080p") throws -> FixtureSet {
        let folder = try Fixtures.directory().appendingPathComponent(name)
        let names = try FileManager.default.contentsOfDirectory(atPath: folder.path).filter { $0.hasSuffix(".pgm") }.sorted()
        let frames = try names.map { try LumaImage(pgm: folder.appendingPathComponent($0)) }
        let text = try String(contentsOf: folder.appendingPathComponent("intrinsics.txt"), encoding: .utf8)
        let intrinsics = text.trimmingCharacters(in: .whitespacesAndNewlines).split(separator: ",").compactMap { Double($0) }
        let lines = try jsonLines(folder.appendingPathComponent("track.jsonl"))
        return FixtureSet(frames: frames, intrinsics: intrinsics, tracked: Array(lines.dropFirst()))
    }

    /// AVFoundation's layout of these intrinsics: column-major, principal point measured from
    /// the top-left corner of the frame (the library moves it to pixel centres).
    var cameraMatrix: [Float] {
        let (fx, fy, cx, cy) = (intrinsics[0], intrinsics[1], intrinsics[2], intrinsics[3])
        return [Float(fx), 0, 0, 0, Float(fy), 0, Float(cx + 0.5), Float(cy + 0.5), 1]
    }

    /// The format the fixture frames have.
    var format: CameraFormatInfo {
        CameraFormatInfo(
            width: frames[0].width, height: frames[0].height, frameRates: [1...60], fullRange420: true, fieldOfViewDegrees: 65
        )
    }

    var configuration: CaptureConfiguration {
        var settings = defaultAppSettings()
        settings.fps = 30
        return CaptureConfiguration(format: format, plan: CapturePlan(settings), model: "Linux", camera: .backWide)
    }

    /// A camera whose one format is the fixture frames', as the camera layer describes it.
    func device(model: String = "Linux", minimumFocusMm: Double? = nil, format: CameraFormatInfo? = nil) -> CameraDevice {
        CameraDevice(model: model, camera: .backWide, minimumFocusMm: minimumFocusMm, formats: [format ?? self.format])
    }
}

func jsonLines(_ url: URL) throws -> [[String: Any]] {
    let text = try String(contentsOf: url, encoding: .utf8)
    return try text.split(separator: "\n").map { line in
        guard let object = try JSONSerialization.jsonObject(with: Data(line.utf8)) as? [String: Any] else {
            throw AppError(message: "\(url.path): a line is not a JSON object")
        }
        return object
    }
}

/// Frames from memory, delivered synchronously on the pipeline's queue by `play`.
class MemoryFrameSource: FrameSource {
    private var handler: ((CameraFrame) -> Void)?
    private var queue: DispatchQueue?

    func deliverFrames(to handler: @escaping (CameraFrame) -> Void, on queue: DispatchQueue) {
        self.handler = handler
        self.queue = queue
    }

    /// Hands `image` over as a padded buffer, as the camera layer does inside the pixel
    /// buffer's lock; returns once the pipeline is done with it. The default exposure is the
    /// one `swift-on-linux.sh` tracks the fixtures at with `jawtrack track`.
    func play(
        _ image: LumaImage,
        layout: PixelLayout = .luma,
        time: Double,
        exposure: Double? = 0.002,
        iso: Double? = nil,
        cameraMatrix: [Float]?,
        lensPosition: Double? = nil,
        adjustingFocus: Bool? = nil,
        truncateTo byteCount: Int? = nil,
        native: AnyObject? = nil
    ) {
        let (bytes, bytesPerRow) = image.padded(layout)
        guard let queue, let handler else {
            XCTFail("no pipeline attached")
            return
        }
        queue.sync {
            bytes.withUnsafeBytes { raw in
                let buffer = FrameBuffer(
                    base: raw.baseAddress!, byteCount: byteCount ?? raw.count, width: image.width, height: image.height,
                    bytesPerRow: bytesPerRow, layout: layout
                )
                handler(CameraFrame(
                    buffer: buffer, time: time, exposure: exposure, iso: iso, cameraMatrix: cameraMatrix,
                    lensPosition: lensPosition, adjustingFocus: adjustingFocus, native: native
                ))
            }
        }
    }
}

/// A camera for the screen model's tests: records what it was asked, and is a frame source.
final class FakeCamera: MemoryFrameSource, CameraControl {
    /// The plans configured (and the setups they came with).
    var configured: [CapturePlan] { setups.map(\.plan) }
    var setups: [CaptureSetup] = []
    var described: [Camera] = []
    var starts = 0
    var locks = 0
    var lockFailure: String?
    var stops = 0
    /// The camera as it describes itself.
    var device: CameraDevice?
    /// Makes `describe` fail.
    var failure: AppError?
    /// Makes `configure` fail.
    var configureFailure: AppError?
    var makeVideo: VideoSinkFactory?
    /// The focus locks asked for, to be answered by the test.
    var focusLocks: [(Result<Double, Error>) -> Void] = []

    func describe(_ camera: Camera, completion: @escaping (Result<CameraDevice, Error>) -> Void) {
        described.append(camera)
        if let failure {
            completion(.failure(failure))
        } else {
            completion(.success(device!))
        }
    }

    func configure(_ setup: CaptureSetup, completion: @escaping (Result<VideoSinkFactory?, Error>) -> Void) {
        setups.append(setup)
        if let configureFailure {
            completion(.failure(configureFailure))
        } else {
            completion(.success(makeVideo))
        }
    }

    func start() {
        starts += 1
    }

    func lockFocus(completion: @escaping (Result<Double, Error>) -> Void) {
        focusLocks.append(completion)
    }

    func lockExposureAndWhiteBalance(onProblem: @escaping (String) -> Void) {
        locks += 1
        if let lockFailure {
            onProblem(lockFailure)
        }
    }

    var exposureCaps: [Double?] = []

    func limitExposure(to seconds: Double?) {
        exposureCaps.append(seconds)
    }

    func stop() {
        stops += 1
    }
}

/// A movie writer that counts frames.
final class MemoryVideoSink: VideoSink {
    let url: URL
    var frames = 0
    var finished = false
    var readyForMore = true

    init(url: URL) {
        self.url = url
    }

    func append(_ frame: CameraFrame) -> Bool {
        guard readyForMore else {
            return false
        }
        frames += 1
        return true
    }

    /// Writes a stand-in movie; as the real writer, reports why not when it could not.
    func finish(completion: @escaping (String?) -> Void) {
        finished = true
        let written = FileManager.default.createFile(atPath: url.path, contents: Data("movie".utf8))
        completion(written ? nil : "could not write the movie \(url.path)")
    }
}

/// A datagram transport in memory: keeps what is sent, and lets the test play the network.
final class MemoryTransport: DatagramTransport {
    var sent: [Data] = []
    var cancelled = false
    private(set) var queue: DispatchQueue?
    private var stateHandler: ((TransportState) -> Void)?
    private var receivedHandler: ((Result<Data, AppError>) -> Void)?
    /// Called once the link has started the transport (its queue known): only then can a test
    /// change the connection's state.
    var onStart: (() -> Void)?

    func start(
        on queue: DispatchQueue,
        state: @escaping (TransportState) -> Void,
        received: @escaping (Result<Data, AppError>) -> Void
    ) {
        self.queue = queue
        stateHandler = state
        receivedHandler = received
        onStart?()
    }

    func send(_ datagram: Data, completion: @escaping (String?) -> Void) {
        sent.append(datagram)
        completion(nil)
    }

    func cancel() {
        cancelled = true
    }

    /// The connection's state changes (on the link's queue, as NWConnection does).
    func become(_ state: TransportState) {
        queue?.sync { stateHandler?(state) }
    }

    /// A datagram arrives from the receiver.
    func receive(_ datagram: Data) {
        queue?.sync { receivedHandler?(.success(datagram)) }
    }
}

/// Little-endian reads from a datagram.
extension Data {
    func u64(at offset: Int) -> UInt64 {
        (0..<8).reduce(UInt64(0)) { $0 | UInt64(self[self.startIndex + offset + $1]) << (8 * UInt64($1)) }
    }

    func u32(at offset: Int) -> UInt32 {
        (0..<4).reduce(UInt32(0)) { $0 | UInt32(self[self.startIndex + offset + $1]) << (8 * UInt32($1)) }
    }

    func f64(at offset: Int) -> Double {
        Double(bitPattern: u64(at: offset))
    }

    func f32(at offset: Int) -> Float {
        Float(bitPattern: u32(at: offset))
    }

    init(hex: String) {
        var bytes: [UInt8] = []
        var index = hex.startIndex
        while index < hex.endIndex {
            let next = hex.index(index, offsetBy: 2)
            bytes.append(UInt8(hex[index..<next], radix: 16)!)
            index = next
        }
        self.init(bytes)
    }

    static func littleEndian(_ value: UInt64) -> Data {
        Data((0..<8).map { UInt8(truncatingIfNeeded: value >> (8 * UInt64($0))) })
    }
}
