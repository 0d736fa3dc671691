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

    /// The golden pose (crates/wire/tests/golden.rs) as the tracker would report it.
    private func goldenResult() -> FrameResult {
        let covariance = [Double](repeating: 0, count: 36)
        return FrameResult(
            frame: 375, t: 12.5, exposureS: nil,
            maxilla: BodyPose(
                cameraFromBody: pose(axisAngle: (0, 0.5, 0), translation: (-20, 10, 100)),
                covariance: covariance, tags: [0, 1, 2], rejectedTags: [], rmsPx: 0.25, blurPx: nil, cellPx: 0
            ),
            mandible: BodyPose(
                cameraFromBody: pose(axisAngle: (0.25, 0.5, 0), translation: (-20, 50, 100)),
                covariance: covariance, tags: [12, 13], rejectedTags: [], rmsPx: 0.5, blurPx: nil, cellPx: 0
            ),
            maxillaFromMandible: pose(axisAngle: (0.25, 0, 0), translation: (0, 40, 0)),
            maxillaScanFromMandibleScan: nil,
            flags: ["mandible:single_tag"],
            overlay: Overlay(tags: [], axes: []),
            detectionMs: 1, poseMs: 1, fps: 30
        )
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
        try session.send(goldenResult())
        session.queue.sync {}
        XCTAssertEqual(session.dropped, 1, "dropped while the connection is not ready")
        transports[0].become(.ready)
        for _ in 0..<3 {
            try session.send(goldenResult())
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

    func testAPlaintextDatagramCarriesTheGoldenBody() throws {
        let golden = try golden()
        let encoder = try LinkEncoder(keyHex: nil, insecurePlaintext: true)
        let session = try link(encoder)
        transports[0].become(.ready)
        try session.send(goldenResult())
        session.queue.sync {}
        let ours = try XCTUnwrap(transports[0].sent.first)
        let reference = try XCTUnwrap(golden.vectors["pose_plaintext"])
        XCTAssertEqual(ours.count, reference.count)
        XCTAssertEqual(ours.prefix(8), reference.prefix(8))
        XCTAssertEqual(ours.f64(at: 32), 12.5)
        XCTAssertEqual(ours.u64(at: 40), 375)
        XCTAssertEqual(ours.u32(at: 48), reference.u32(at: 48), "the same bodies present")
        XCTAssertEqual(ours.u32(at: 52), reference.u32(at: 52), "the same flags")
        for slot in 0..<21 {
            XCTAssertEqual(ours.f64(at: 56 + 8 * slot), reference.f64(at: 56 + 8 * slot), accuracy: 1e-12, "pose number \(slot)")
        }
        for body in 0..<2 {
            XCTAssertEqual(ours.u32(at: 224 + 12 * body), reference.u32(at: 224 + 12 * body), "tag mask")
            XCTAssertEqual(ours[ours.startIndex + 228 + 12 * body], reference[reference.startIndex + 228 + 12 * body], "tag count")
            XCTAssertEqual(ours.f32(at: 232 + 12 * body), reference.f32(at: 232 + 12 * body), "RMS")
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
