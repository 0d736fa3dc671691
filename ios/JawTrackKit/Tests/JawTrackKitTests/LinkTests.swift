import Foundation
import JawTrackCore
import JawTrackKit
import XCTest

/// The link against the golden datagrams of `fixtures/wire` and an in-memory network.
final class LinkTests: XCTestCase {
    private struct Golden {
        let keyHex: String
        let keyId: String
        let vectors: [String: Data]
    }

    private func golden() throws -> Golden {
        let url = try Fixtures.directory().appendingPathComponent("wire-golden.json")
        let doc = try XCTUnwrap(try JSONSerialization.jsonObject(with: Data(contentsOf: url)) as? [String: Any])
        var vectors: [String: Data] = [:]
        for vector in try XCTUnwrap(doc["vectors"] as? [[String: Any]]) {
            vectors[try XCTUnwrap(vector["name"] as? String)] = Data(hex: try XCTUnwrap(vector["hex"] as? String))
        }
        return Golden(keyHex: try XCTUnwrap(doc["key_hex"] as? String), keyId: try XCTUnwrap(doc["key_id"] as? String), vectors: vectors)
    }

    /// A tracker that has just tracked the first fixture frame (both jaws in view, at 12.5 s),
    /// and that frame's result: the link takes the result from the tracker, not from the app.
    private func tracked() throws -> (Tracker, FrameResult) {
        let set = try FixtureSet.load()
        let image = set.frames[0]
        let k = set.intrinsics
        let tracker = try Tracker(settings: defaultSettings(), markerJson: nil)
        let result = try tracker.trackLuma(
            luma: Data(image.pixels), width: UInt32(image.width), height: UInt32(image.height),
            bytesPerRow: UInt32(image.width),
            intrinsics: Intrinsics(fx: k[0], fy: k[1], cx: k[2], cy: k[3], k1: k[4], k2: k[5]),
            t: 12.5, exposureS: nil
        )
        XCTAssertNotNil(result.maxillaFromMandible, "the fixture frame shows both jaws")
        return (tracker, result)
    }

    private var transports: [MemoryTransport] = []
    private var scheduled: [(Double, () -> Void)] = []
    private var acks: [(LinkAck, Double)] = []
    private var problems: [String?] = []
    private var now = 1000.0
    /// The links made, kept alive for the test's length (a released link ignores its transport).
    private var sessions: [LinkSession] = []

    private func link(_ encoder: LinkEncoder, host: String = "192.168.1.20", port: UInt32 = 5005) throws -> LinkSession {
        let queue = DispatchQueue(label: "test.link")
        let session = try LinkSession(
            host: host, port: port, encoder: encoder, queue: queue,
            clock: { [unowned self] in now },
            schedule: { [unowned self] delay, work in scheduled.append((delay, work)) },
            makeTransport: { [unowned self] host, port in
                XCTAssertEqual(host, "192.168.1.20")
                XCTAssertEqual(port, 5005)
                let transport = MemoryTransport()
                transports.append(transport)
                return transport
            },
            onAck: { [unowned self] in acks.append(($0, $1)) },
            onProblem: { [unowned self] in problems.append($0) }
        )
        session.start()
        queue.sync {}
        sessions.append(session)
        return session
    }

    func testSealedDatagramsHaveTheGoldenLayoutAndCountUp() throws {
        let golden = try golden()
        let encoder = try LinkEncoder(keyHex: golden.keyHex, insecurePlaintext: false)
        XCTAssertEqual(encoder.keyId(), golden.keyId)
        let session = try link(encoder)
        let (tracker, result) = try tracked()
        try session.send(frame: result.frame, of: tracker)
        session.queue.sync {}
        XCTAssertEqual(session.dropped, 1, "dropped while the connection is not ready")
        transports[0].become(.ready)
        for _ in 0..<3 {
            try session.send(frame: result.frame, of: tracker)
        }
        session.queue.sync {}
        let sent = transports[0].sent
        XCTAssertEqual(sent.count, 3)
        let reference = try XCTUnwrap(golden.vectors["pose_sealed"])
        for (index, datagram) in sent.enumerated() {
            XCTAssertEqual(datagram.count, reference.count)
            XCTAssertEqual(datagram.prefix(8), reference.prefix(8), "magic JAWT, version, pose, sealed, reserved")
            XCTAssertEqual(datagram.u64(at: 8), encoder.sessionId())
            XCTAssertEqual(datagram.u64(at: 16), UInt64(index + 1), "sequence numbers count up from the dropped one")
        }
    }

    func testAPlaintextDatagramCarriesTheLibrarysBodyInTheGoldenLayout() throws {
        let golden = try golden()
        let encoder = try LinkEncoder(keyHex: nil, insecurePlaintext: true)
        let session = try link(encoder)
        transports[0].become(.ready)
        let (tracker, result) = try tracked()
        try session.send(frame: result.frame, of: tracker)
        session.queue.sync {}
        let ours = try XCTUnwrap(transports[0].sent.first)
        let layout = try XCTUnwrap(golden.vectors["pose_plaintext"])
        XCTAssertEqual(ours.count, layout.count)
        XCTAssertEqual(ours.prefix(8), layout.prefix(8), "magic JAWT, version, pose, plaintext, reserved")
        XCTAssertEqual(ours.f64(at: 32), 12.5)
        XCTAssertEqual(ours.u64(at: 40), result.frame)
        XCTAssertEqual(ours.u32(at: 48), 7, "both bodies and the jaw present")
        // The body is the library's encoding of the tracker's result, carried unchanged.
        let direct = try LinkEncoder(keyHex: nil, insecurePlaintext: true).encode(tracker: tracker, frame: result.frame)
        XCTAssertEqual(ours.count, direct.count)
        XCTAssertEqual(ours.dropFirst(32), direct.dropFirst(32))
        let relative = try XCTUnwrap(result.maxillaFromMandible)
        // Poses from byte 56, seven numbers each (w, x, y, z, then the translation); the jaw third.
        XCTAssertEqual(ours.f64(at: 56 + 8 * (14 + 4)), relative[3], accuracy: 1e-9, "maxilla_from_mandible x")
    }

    func testOnlyTheFrameJustTrackedIsSent() throws {
        let session = try link(try LinkEncoder(keyHex: nil, insecurePlaintext: true))
        let (tracker, result) = try tracked()
        XCTAssertThrowsError(try session.send(frame: result.frame + 1, of: tracker)) { error in
            guard case JawTrackError.InvalidArgument = error else {
                return XCTFail("expected InvalidArgument, got \(error)")
            }
            XCTAssertTrue(userText(error).contains("not the last frame tracked"), userText(error))
        }
    }

    /// The receiver's acknowledgement of `session` in plaintext (docs/wire.md): header, then
    /// session, highest sequence, accepted, lost, rejected.
    private func ack(of session: UInt64, lost: UInt64) -> Data {
        var d = Data("JAWT".utf8) + Data([1, 2, 0, 0])
        for value in [0xFEDC_BA98_7654_3210, 7, 1_795_000_000_010, session, 41, 40, lost, 5] as [UInt64] {
            d += Data.littleEndian(value)
        }
        return d
    }

    func testTheLightIsGreenOnlyWithinASecondOfAnAcknowledgement() throws {
        let encoder = try LinkEncoder(keyHex: nil, insecurePlaintext: true)
        _ = try link(encoder)
        var light = AckLight()
        XCTAssertFalse(light.isGreen(at: now))
        XCTAssertEqual(light.text(at: now), "LINK: no ack")
        transports[0].become(.ready)
        transports[0].receive(ack(of: encoder.sessionId(), lost: 2))
        let (received, at) = try XCTUnwrap(acks.last)
        XCTAssertEqual(received, LinkAck(highestSeq: 41, accepted: 40, lost: 2, rejected: 5))
        light.acknowledged(received, at: at)
        XCTAssertTrue(light.isGreen(at: now + 0.99))
        XCTAssertEqual(light.text(at: now + 0.5), "LINK lost 2")
        XCTAssertFalse(light.isGreen(at: now + 1.0), "no acknowledgement for a second: red")
        XCTAssertEqual(light.text(at: now + 1.5), "LINK: no ack (lost 2)")
        transports[0].receive(ack(of: encoder.sessionId() &+ 1, lost: 0))
        XCTAssertEqual(acks.count, 1, "another session's acknowledgement is not ours")
        XCTAssertTrue(try XCTUnwrap(problems.last ?? nil).hasPrefix("Not an acknowledgement of this link"))
    }

    func testTheGoldenSealedAckOfAnotherSessionIsRefused() throws {
        let golden = try golden()
        let encoder = try LinkEncoder(keyHex: golden.keyHex, insecurePlaintext: false)
        _ = try link(encoder)
        transports[0].become(.ready)
        transports[0].receive(try XCTUnwrap(golden.vectors["ack_sealed"]))
        transports[0].receive(try XCTUnwrap(golden.vectors["ack_sealed"]))
        XCTAssertTrue(acks.isEmpty)
        XCTAssertEqual(problems.compactMap { $0 }.filter { $0.hasPrefix("Not an acknowledgement") }.count, 1, "said once")
    }

    func testAFailedConnectionIsReplacedWithBackoff() throws {
        let session = try link(try LinkEncoder(keyHex: nil, insecurePlaintext: true))
        transports[0].become(.failed("no route"))
        XCTAssertTrue(transports[0].cancelled)
        XCTAssertEqual(problems.last, "The link failed: no route. Reconnecting in 1 s.")
        XCTAssertEqual(scheduled.map(\.0), [1])
        session.queue.sync { scheduled[0].1() }
        XCTAssertEqual(transports.count, 2)
        XCTAssertEqual(session.reconnects, 1)
        transports[1].become(.failed("no route"))
        XCTAssertEqual(scheduled.map(\.0), [1, 2])
        session.queue.sync { scheduled[1].1() }
        transports[2].become(.ready)
        XCTAssertNil(problems.last ?? nil, "the problem clears once connected")
        transports[0].become(.ready)
        session.stop()
        session.queue.sync {}
        XCTAssertTrue(transports[2].cancelled)
        transports[2].become(.failed("gone"))
        XCTAssertEqual(scheduled.count, 2, "a stopped link does not reconnect")
    }

    func testWaitingForTheNetworkIsShown() throws {
        _ = try link(try LinkEncoder(keyHex: nil, insecurePlaintext: true))
        transports[0].become(.waiting("Local network access is not allowed"))
        XCTAssertEqual(problems.last, "Waiting for the network: Local network access is not allowed")
    }

    func testBadAddressesAndKeysAreRefused() throws {
        let encoder = try LinkEncoder(keyHex: nil, insecurePlaintext: true)
        XCTAssertThrowsError(try link(encoder, host: "  ")) { XCTAssertTrue(userText($0).contains("No receiver host")) }
        XCTAssertThrowsError(try link(encoder, port: 0)) { XCTAssertTrue(userText($0).contains("not a UDP port")) }
        XCTAssertThrowsError(try link(encoder, port: 70000)) { XCTAssertTrue(userText($0).contains("not a UDP port")) }
        XCTAssertThrowsError(try LinkEncoder(keyHex: "0011", insecurePlaintext: false)) { error in
            guard case JawTrackError.InvalidKey = error else {
                return XCTFail("expected InvalidKey, got \(error)")
            }
            XCTAssertFalse(userText(error).isEmpty)
        }
        XCTAssertThrowsError(try LinkEncoder(keyHex: nil, insecurePlaintext: false))
    }
}
