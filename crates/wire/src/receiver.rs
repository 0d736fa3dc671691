//! A receiver's handling of each datagram: decoded, judged by the [`Link`] accounting, turned
//! into a recording line when accepted, and answered with an acknowledgement at most ten times
//! a second per phone (enough for the app's link light).

use crate::link::{Counters, Link, LinkConfig, Verdict};
use crate::{Ack, Message, Security, decode, encode_ack};
use jawtrack_recording::{FrameRecord, RecordingHeader};
use std::net::SocketAddr;
use std::time::{Duration, Instant};

/// The shortest time between two acknowledgements to the same phone.
pub const ACK_INTERVAL: Duration = Duration::from_millis(100);

/// What one datagram gave.
#[derive(Debug, Default)]
pub struct Received {
    /// The frame to record, and its sequence number, when the datagram was accepted.
    pub frame: Option<(FrameRecord, u64)>,
    /// An acknowledgement to send back to the datagram's sender, when one is due.
    pub ack: Option<Vec<u8>>,
}

/// The receiving end of the link.
#[derive(Debug)]
pub struct Receiver {
    link: Link,
    security: Security,
    /// This receiver's own session id, in its acknowledgements' headers.
    session: u64,
    acks_sent: u64,
    last_ack: Option<(SocketAddr, Instant)>,
}

/// A receiver's recording header: it records whatever sessions arrive (each frame carries its
/// phone's), under the key it opened them with, and names where it listened and the clock skew
/// it allowed (s).
pub fn recording_header(listen: SocketAddr, max_clock_skew_s: f64, security: &Security) -> RecordingHeader {
    let mut header = RecordingHeader::new("jawtrack receive");
    header.session = None;
    header.key_id = security.key_id();
    header.settings = serde_json::json!({ "listen": listen.to_string(), "max_clock_skew_s": max_clock_skew_s });
    header
}

/// What a receiver run did, as one JSON object: the counts `c`, the acknowledgements sent, the
/// run's length (s) and the CPU time it took (s, when known) and its share of one core.
pub fn run_summary(c: &Counters, acks: u64, elapsed_s: f64, cpu_s: Option<f64>) -> serde_json::Value {
    let mut v = c.to_json();
    v["acks_sent"] = acks.into();
    v["duration_s"] = elapsed_s.into();
    v["cpu_s"] = cpu_s.into();
    v["cpu_share_of_one_core"] = cpu_s.map(|c| c / elapsed_s.max(1e-9)).into();
    v
}

/// The address a phone should send to when the receiver listens on `listen`: that address, or,
/// when it listens on every interface, the one this computer uses toward the network (learnt
/// from a connected UDP socket: no packet is sent).
pub fn reachable_address(listen: SocketAddr) -> std::net::IpAddr {
    if !listen.ip().is_unspecified() {
        return listen.ip();
    }
    std::net::UdpSocket::bind("0.0.0.0:0")
        .and_then(|s| s.connect("192.0.2.1:9").and_then(|()| s.local_addr()))
        .map(|a| a.ip())
        .unwrap_or(listen.ip())
}

/// CPU time of this process so far (s), from /proc (Linux only).
pub fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name (which may hold spaces) start at the last ')'.
    let fields: Vec<&str> = stat.get(stat.rfind(')')? + 2..)?.split_whitespace().collect();
    let ticks: f64 = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    // USER_HZ is 100 on every Linux architecture we run on.
    Some(ticks / 100.0)
}

impl Receiver {
    /// A receiver opening datagrams with `security`, its acknowledgements under `session`.
    pub fn new(config: LinkConfig, security: Security, session: u64) -> Receiver {
        Receiver { link: Link::new(config), security, session, acks_sent: 0, last_ack: None }
    }

    /// Handles one datagram from `from`, arrived at `now_unix_ms` (the receiver's clock) and
    /// `now` (for the acknowledgements' pacing).
    pub fn datagram(&mut self, bytes: &[u8], from: SocketAddr, now_unix_ms: u64, now: Instant) -> Received {
        let (header, packet) = match decode(bytes, &self.security) {
            Ok(Message::Pose(h, p)) => (h, p),
            Ok(Message::Ack(..)) => {
                self.link.count_rejection("not_a_pose");
                return Received::default();
            }
            Err(e) => {
                self.link.reject(&e);
                return Received::default();
            }
        };
        let mut out = Received::default();
        if let Verdict::Accept { .. } = self.link.check(&header, now_unix_ms) {
            out.frame = Some((packet.to_record(&header, now_unix_ms as f64 / 1e3), header.seq));
        }
        let due = self.last_ack.is_none_or(|(peer, t)| peer != from || now.duration_since(t) >= ACK_INTERVAL);
        if due && let Some(s) = self.link.session(header.session) {
            let ack = Ack {
                session: s.session,
                highest_seq: s.highest_seq,
                accepted: s.accepted,
                lost: s.lost,
                rejected: self.link.counters().rejected_total(),
            };
            out.ack = Some(encode_ack((self.session, self.acks_sent, now_unix_ms), &ack, &self.security));
        }
        out
    }

    /// Notes that the acknowledgement [`Receiver::datagram`] gave was sent to `to` at `at` (a
    /// phone that vanished is not an error, so an unsent one is simply not counted).
    pub fn ack_sent(&mut self, to: SocketAddr, at: Instant) {
        self.acks_sent += 1;
        self.last_ack = Some((to, at));
    }

    /// Acknowledgements sent.
    pub fn acks_sent(&self) -> u64 {
        self.acks_sent
    }

    /// The accounting so far.
    pub fn link(&self) -> &Link {
        &self.link
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_summary_adds_the_run_to_the_counts() {
        let c = Counters { received: 3, accepted: 2, ..Counters::default() };
        let v = run_summary(&c, 1, 2.0, Some(0.5));
        assert_eq!((v["received"].as_u64(), v["acks_sent"].as_u64()), (Some(3), Some(1)));
        assert_eq!((v["cpu_s"].as_f64(), v["cpu_share_of_one_core"].as_f64()), (Some(0.5), Some(0.25)));
        assert!(run_summary(&c, 0, 1.0, None)["cpu_share_of_one_core"].is_null());
        assert_eq!(c.describe(), "received 3, accepted 2, lost 0, reordered 0, duplicated 0, rejected 0");
    }

    #[test]
    fn a_receiver_on_one_address_is_reached_there() {
        let listen: SocketAddr = "192.168.1.20:5005".parse().expect("address");
        assert_eq!(reachable_address(listen), listen.ip());
        let any: SocketAddr = "0.0.0.0:5005".parse().expect("address");
        // Without a network the unspecified address comes back; with one, a concrete address.
        let reached = reachable_address(any);
        assert!(reached.is_ipv4(), "{reached}");
    }

    #[test]
    fn a_plaintext_receivers_header_names_no_key() {
        let h = recording_header("127.0.0.1:5005".parse().expect("address"), 60.0, &Security::Plaintext);
        assert_eq!((h.session, h.key_id), (None, None));
        assert_eq!(h.settings["listen"], "127.0.0.1:5005");
    }
}
