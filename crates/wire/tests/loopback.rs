//! The send and receive loops against each other on 127.0.0.1: an impaired replay whose
//! counts the receiver must find exactly, every accepted frame handed to the sink once.

use jawtrack_recording::FrameRecord;
use jawtrack_wire::options::LinkError;
use jawtrack_wire::receiver::{ReceiveOptions, ReceiveSink, receive};
use jawtrack_wire::replay::{ReplayOptions, send_recording};
use jawtrack_wire::{Header, Key, Kind, PosePacket, Security};
use std::net::UdpSocket;
use std::sync::atomic::AtomicBool;

/// Keeps the sequence numbers of the frames it is given.
#[derive(Default)]
struct Seqs(Vec<u64>);

impl ReceiveSink for Seqs {
    type Error = LinkError;
    fn frame(&mut self, _: &FrameRecord, seq: u64) -> Result<(), LinkError> {
        self.0.push(seq);
        Ok(())
    }
}

/// Three frames of a still jaw, to be cycled through.
fn frames() -> Vec<FrameRecord> {
    let header = Header { kind: Kind::Pose, session: 1, seq: 0, sent_unix_ms: 0 };
    let packet =
        |i| PosePacket { t: 0.0, frame: i, maxilla: None, mandible: None, maxilla_from_mandible: None, flags: 0 };
    (0..3).map(|i| packet(i).to_record(&header, 0.0)).collect()
}

#[test]
fn an_impaired_replay_is_counted_exactly_by_the_receiver() {
    let socket = UdpSocket::bind("127.0.0.1:0").expect("socket");
    let to = socket.local_addr().expect("address");
    let security = Security::Sealed(Key::from_bytes([9; 32]));
    let stop = AtomicBool::new(false);
    let listen = ReceiveOptions { duration: Some(30.0), idle_exit: Some(0.5), ..ReceiveOptions::default() };
    let replay = ReplayOptions { rate: 1000.0, count: Some(300), loss: 0.2, reorder: 0.05, duplicate: 0.05, seed: 7 };
    let (sent, (got, seqs)) = std::thread::scope(|s| {
        let receiver = s.spawn(|| {
            let mut seqs = Seqs::default();
            (receive(&socket, security.clone(), &listen, &stop, &mut seqs).expect("received"), seqs.0)
        });
        let mut done = 0;
        let sent = send_recording(&frames(), to, security.clone(), &replay, |n| done = n).expect("sent");
        assert_eq!(done, 300, "progress heard every datagram");
        (sent, receiver.join().expect("the receiver thread"))
    });
    let (i, c) = (&sent.impairment, &got.counters);
    assert!(i.dropped > 20 && i.reordered > 0 && i.duplicated > 0, "{i:?}");
    assert_eq!((c.received, c.lost, c.reordered, c.duplicated), (i.sent, i.dropped, i.reordered, i.duplicated));
    assert_eq!((c.accepted, c.rejected_total()), (300 - i.dropped, 0));
    let mut unique = seqs.clone();
    unique.sort_unstable();
    unique.dedup();
    assert_eq!((seqs.len() as u64, unique.len()), (c.accepted, seqs.len()), "each accepted frame once");
    assert!(sent.acks.read > 0 && sent.acks.read <= got.acks_sent, "{:?} of {}", sent.acks, got.acks_sent);
    assert_eq!(sent.acks.last.map(|a| a.session), Some(sent.session));
}
