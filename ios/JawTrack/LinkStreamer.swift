import Foundation
import JawTrackCore
import Network

/// Streams results to the desktop receiver (`jawtrack receive`) over UDP: one datagram per
/// frame, sealed by the library's `LinkEncoder` (`docs/wire.md`), and reads the receiver's
/// acknowledgements back through it, so the screen's link light is green only while they
/// arrive. The connection and its state live on the streamer's own serial queue.
final class LinkStreamer {
    private let connection: NWConnection
    private let encoder: LinkEncoder
    private let queue = DispatchQueue(label: "org.jawtrack.link")
    private let onAck: @Sendable (LinkAck) -> Void
    private let onProblem: @Sendable (String) -> Void
    // Touched on `queue` only.
    private var ready = false
    private var receiving = false
    private var stopped = false
    private var lastProblem: String?

    /// A streamer to `host`:`port` (not started).
    init(
        host: String,
        port: UInt32,
        encoder: LinkEncoder,
        onAck: @escaping @Sendable (LinkAck) -> Void,
        onProblem: @escaping @Sendable (String) -> Void
    ) throws {
        guard port > 0, let endpointPort = NWEndpoint.Port(String(port)) else {
            throw AppError(message: "Receiver port \(port) is not a UDP port.")
        }
        connection = NWConnection(host: NWEndpoint.Host(host), port: endpointPort, using: .udp)
        self.encoder = encoder
        self.onAck = onAck
        self.onProblem = onProblem
    }

    deinit {
        connection.cancel()
    }

    func start() {
        connection.stateUpdateHandler = { [weak self] state in
            self?.changed(to: state)
        }
        connection.start(queue: queue)
    }

    /// Stops sending and receiving for good.
    func stop() {
        queue.async {
            self.stopped = true
            self.ready = false
            self.connection.cancel()
        }
    }

    /// Seals `result` into the next datagram and sends it (dropped while the connection is not
    /// ready: a late pose is worthless).
    func send(_ result: FrameResult) throws {
        let datagram = try encoder.encode(result: result)
        queue.async { [weak self] in
            guard let self, self.ready, !self.stopped else {
                return
            }
            self.connection.send(content: datagram, completion: .contentProcessed { [weak self] error in
                if let error {
                    self?.report("Sending failed: \(error.localizedDescription)")
                }
            })
        }
    }

    private func changed(to state: NWConnection.State) {
        switch state {
        case .ready:
            ready = true
            if !receiving {
                receiving = true
                receiveNext()
            }
        case .waiting(let error):
            ready = false
            report("Waiting for the network: \(error.localizedDescription)")
        case .failed(let error):
            ready = false
            report("The link failed: \(error.localizedDescription). Turn Transmit off and on.")
        case .cancelled:
            ready = false
        default:
            break
        }
    }

    /// Reads one datagram from the receiver, then asks for the next; after an error (e.g. the
    /// receiver's port is closed) tries again a second later.
    private func receiveNext() {
        connection.receiveMessage { [weak self] data, _, _, error in
            guard let self, !self.stopped else {
                return
            }
            if let data, !data.isEmpty {
                do {
                    let ack = try self.encoder.readAck(datagram: data)
                    self.lastProblem = nil
                    self.onAck(ack)
                } catch {
                    self.report(userText(error))
                }
            }
            if let error {
                self.report("Receiving failed: \(error.localizedDescription)")
                self.queue.asyncAfter(deadline: .now() + 1) { [weak self] in
                    self?.receiveNext()
                }
            } else {
                self.receiveNext()
            }
        }
    }

    /// Passes a problem on once, not once per datagram.
    private func report(_ problem: String) {
        guard problem != lastProblem else {
            return
        }
        lastProblem = problem
        onProblem(problem)
    }
}
