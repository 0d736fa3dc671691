// Adapts Network's NWConnection (UDP) to JawTrackKit's DatagramTransport: its states as
// TransportState, every datagram received (re-armed a second after an error), sends, cancel.
// Everything runs on the queue the link gives to `start`.
import Foundation
import JawTrackKit
import Network

final class UDPTransport: DatagramTransport {
    private let connection: NWConnection
    // Touched on the link's queue only.
    private var receiving = false
    private var cancelled = false

    init(host: String, port: UInt16) throws {
        guard let endpointPort = NWEndpoint.Port(rawValue: port) else { throw PlatformText.invalidPort(port) }
        connection = NWConnection(host: NWEndpoint.Host(host), port: endpointPort, using: .udp)
    }

    func start(
        on queue: DispatchQueue, state: @escaping (TransportState) -> Void, received: @escaping (Result<Data, AppError>) -> Void
    ) {
        connection.stateUpdateHandler = { [weak self] new in
            switch new {
            case .ready: state(.ready)
            case .waiting(let error): state(.waiting(error.localizedDescription))
            case .failed(let error): state(.failed(error.localizedDescription))
            case .cancelled: state(.cancelled)
            default: state(.preparing)
            }
            guard case .ready = new, let self, !self.receiving else { return }
            self.receiving = true
            self.receive(on: queue, received)
        }
        connection.start(queue: queue)
    }

    private func receive(on queue: DispatchQueue, _ received: @escaping (Result<Data, AppError>) -> Void) {
        connection.receiveMessage { [weak self] data, _, _, error in
            guard let self, !self.cancelled else { return }
            if let data, !data.isEmpty { received(.success(data)) }
            guard let error else { return self.receive(on: queue, received) }
            received(.failure(AppError(message: error.localizedDescription)))
            queue.asyncAfter(deadline: .now() + 1) { [weak self] in self?.receive(on: queue, received) }
        }
    }

    func send(_ datagram: Data, completion: @escaping (String?) -> Void) {
        connection.send(content: datagram, completion: .contentProcessed { completion($0?.localizedDescription) })
    }

    func cancel() {
        cancelled = true
        connection.cancel()
    }
}
