import Foundation
import JawTrackCore

/// A datagram connection's state, as the transport reports it.
public enum TransportState: Equatable {
    case preparing
    case ready
    /// No usable network path yet (Wi-Fi off, local network not allowed).
    case waiting(String)
    /// The connection is gone for good; the link makes a new one.
    case failed(String)
    case cancelled
}

/// A UDP connection to the receiver (NWConnection in the app, memory in tests). Every callback
/// must come on the queue given to `start`.
public protocol DatagramTransport: AnyObject {
    func start(
        on queue: DispatchQueue,
        state: @escaping (TransportState) -> Void,
        received: @escaping (Result<Data, AppError>) -> Void
    )
    /// Sends one datagram; `completion` gets nil when it left, else why not.
    func send(_ datagram: Data, completion: @escaping (String?) -> Void)
    func cancel()
}

/// Makes a transport to host:port.
public typealias TransportFactory = (_ host: String, _ port: UInt16) throws -> DatagramTransport

/// The link light: green only while the receiver's acknowledgements arrive (one within the last
/// second), red otherwise, with the receiver's loss count.
public struct AckLight: Equatable {
    /// How recent the last acknowledgement must be for green (s).
    public static let window = 1.0

    public private(set) var lastAck: LinkAck?
    public private(set) var lastAckAt: Double?

    public init() {}

    public mutating func acknowledged(_ ack: LinkAck, at time: Double) {
        lastAck = ack
        lastAckAt = time
    }

    public func isGreen(at time: Double) -> Bool {
        guard let lastAckAt else {
            return false
        }
        return time - lastAckAt < Self.window && time >= lastAckAt
    }

    /// The label beside the light.
    public func text(at time: Double) -> String {
        guard let lastAck else {
            return "LINK: no ack"
        }
        return isGreen(at: time) ? "LINK lost \(lastAck.lost)" : "LINK: no ack (lost \(lastAck.lost))"
    }
}

/// Streams results to the desktop receiver (`jawtrack receive`): one datagram per frame, sealed
/// by the library's `LinkEncoder` (`docs/wire.md`), and reads the acknowledgements back through
/// it. Datagrams are dropped while the connection is not ready (a late pose is worthless). A
/// failed connection is replaced after 1, 2, 4, 8, 8 … s until the link is stopped. Everything
/// runs on `queue` (hence `@unchecked Sendable`: every field is confined to it).
public final class LinkSession: @unchecked Sendable {
    public let queue: DispatchQueue
    private let encoder: LinkEncoder
    private let host: String
    private let port: UInt16
    private let makeTransport: TransportFactory
    private let clock: () -> Double
    private let schedule: (Double, @escaping @Sendable () -> Void) -> Void
    private let onAck: (LinkAck, Double) -> Void
    private let onProblem: (String?) -> Void
    // Touched on `queue` only.
    private var transport: DatagramTransport?
    private var ready = false
    private var stopped = false
    private var lastProblem: String?
    private var retryDelay = 1.0
    public private(set) var sent: UInt64 = 0
    public private(set) var dropped: UInt64 = 0
    public private(set) var reconnects: UInt64 = 0

    /// A link to `host`:`port` (validated: a blank host or port 0 is refused), not started.
    /// `onAck` gets each acknowledgement with its arrival time; `onProblem` a problem to show,
    /// or nil when it is over. Both are called on `queue`.
    public init(
        host: String,
        port: UInt32,
        encoder: LinkEncoder,
        queue: DispatchQueue = DispatchQueue(label: "org.jawtrack.link"),
        clock: @escaping () -> Double = { Date().timeIntervalSince1970 },
        schedule: ((Double, @escaping @Sendable () -> Void) -> Void)? = nil,
        makeTransport: @escaping TransportFactory,
        onAck: @escaping (LinkAck, Double) -> Void,
        onProblem: @escaping (String?) -> Void
    ) throws {
        let host = host.trimmingCharacters(in: .whitespacesAndNewlines)
        guard !host.isEmpty else {
            throw AppError(message: "No receiver host is set; enter it in Settings or scan the receiver's QR code.")
        }
        guard port > 0, port <= UInt32(UInt16.max) else {
            throw AppError(message: "Receiver port \(port) is not a UDP port (1–65535).")
        }
        self.host = host
        self.port = UInt16(port)
        self.encoder = encoder
        self.queue = queue
        self.clock = clock
        self.schedule = schedule ?? { delay, work in queue.asyncAfter(deadline: .now() + delay, execute: work) }
        self.makeTransport = makeTransport
        self.onAck = onAck
        self.onProblem = onProblem
    }

    public func start() {
        queue.async { self.connect() }
    }

    /// Stops sending and receiving for good.
    public func stop() {
        queue.async {
            self.stopped = true
            self.ready = false
            self.transport?.cancel()
            self.transport = nil
        }
    }

    /// Seals frame `frame`, the one `tracker` just tracked, into the next datagram and sends it,
    /// or drops it while not connected. The library takes the result from the tracker itself.
    /// Throws only when that frame is not the tracker's last (a frame is sent as it is tracked).
    public func send(frame: UInt64, of tracker: Tracker) throws {
        let datagram = try encoder.encode(tracker: tracker, frame: frame)
        queue.async {
            guard !self.stopped, self.ready, let transport = self.transport else {
                self.dropped += 1
                return
            }
            self.sent += 1
            transport.send(datagram) { [weak self] problem in
                if let problem {
                    self?.report("Sending failed: \(problem)")
                }
            }
        }
    }

    private func connect() {
        guard !stopped else {
            return
        }
        do {
            let transport = try makeTransport(host, port)
            self.transport = transport
            transport.start(on: queue, state: { [weak self, weak transport] state in
                guard let self, let transport, transport === self.transport else {
                    return
                }
                self.changed(to: state)
            }, received: { [weak self] datagram in
                self?.received(datagram)
            })
        } catch {
            report("The receiver \(host):\(port) cannot be reached: \(userText(error))")
        }
    }

    private func changed(to state: TransportState) {
        switch state {
        case .ready:
            ready = true
            retryDelay = 1
            report(nil)
        case .waiting(let why):
            ready = false
            report("Waiting for the network: \(why)")
        case .failed(let why):
            ready = false
            transport?.cancel()
            transport = nil
            let delay = retryDelay
            retryDelay = min(retryDelay * 2, 8)
            report("The link failed: \(why). Reconnecting in \(Int(delay)) s.")
            schedule(delay) { [weak self] in
                guard let self, !self.stopped else {
                    return
                }
                self.reconnects += 1
                self.connect()
            }
        case .cancelled, .preparing:
            ready = false
        }
    }

    private func received(_ datagram: Result<Data, AppError>) {
        guard !stopped else {
            return
        }
        switch datagram {
        case .success(let data):
            do {
                let ack = try encoder.readAck(datagram: data)
                report(nil)
                onAck(ack, clock())
            } catch {
                report("Not an acknowledgement of this link: \(userText(error))")
            }
        case .failure(let error):
            report("Receiving failed: \(error.message)")
        }
    }

    /// Passes a problem on once, not once per datagram; nil clears it.
    private func report(_ problem: String?) {
        guard problem != lastProblem else {
            return
        }
        lastProblem = problem
        onProblem(problem)
    }
}
