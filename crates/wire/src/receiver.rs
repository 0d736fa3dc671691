//! A receiver's handling of each datagram: decoded, judged by the [`Link`] accounting, turned
//! into a recording line when accepted, and answered with an acknowledgement at most ten times
//! a second per phone (enough for the app's link light).

use crate::link::{Link, LinkConfig, Verdict};
use crate::{Ack, Message, Security, decode, encode_ack};
use jawtrack_recording::FrameRecord;
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
