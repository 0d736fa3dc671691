//! The phone simulator's side of a replay (`jawtrack send`): the link impaired on purpose
//! (datagrams dropped, held back behind the next one, or sent twice, each with its
//! probability), the receiver's acknowledgements tallied, and the run summed up as JSON.

use crate::{Ack, Session};
use rand::Rng;

/// Deliberate loss, reordering and duplication of the datagrams of a replay, and their counts.
#[derive(Debug, Clone, Default)]
pub struct Impairment {
    /// Probability of dropping a datagram (its sequence number is used, so the receiver sees a
    /// gap).
    pub loss: f64,
    /// Probability of holding a datagram back and sending it after the next one.
    pub reorder: f64,
    /// Probability of sending a datagram twice.
    pub duplicate: f64,
    /// Datagrams to send (copies counted).
    pub sent: u64,
    /// Datagrams dropped.
    pub dropped: u64,
    /// Datagrams sent after the next one.
    pub reordered: u64,
    /// Second copies sent.
    pub duplicated: u64,
    held: Option<Vec<u8>>,
}

impl Impairment {
    /// No datagram touched until a probability is set.
    pub fn new(loss: f64, reorder: f64, duplicate: f64) -> Impairment {
        Impairment { loss, reorder, duplicate, ..Impairment::default() }
    }

    /// What to send now for `datagram`, in order, each copy on its own: nothing when it is
    /// dropped or held back, else it (maybe twice) and then the one held back. The `last`
    /// datagram of a replay is always sent, so that every loss is visible.
    pub fn pass(&mut self, datagram: Vec<u8>, last: bool, rng: &mut impl Rng) -> Vec<Vec<u8>> {
        let mut out = Vec::new();
        if !last && rng.random_bool(self.loss) {
            self.dropped += 1;
        } else if !last && self.held.is_none() && rng.random_bool(self.reorder) {
            self.held = Some(datagram);
        } else {
            self.copies(datagram, rng, &mut out);
            if let Some(h) = self.held.take() {
                self.copies(h, rng, &mut out);
                self.reordered += 1;
            }
        }
        out
    }

    fn copies(&mut self, d: Vec<u8>, rng: &mut impl Rng, out: &mut Vec<Vec<u8>>) {
        if rng.random_bool(self.duplicate) {
            out.push(d.clone());
            self.duplicated += 1;
            self.sent += 1;
        }
        out.push(d);
        self.sent += 1;
    }
}

/// The receiver's acknowledgements as a sender reads them: read, refused (not opened by the
/// key), and the last one.
#[derive(Debug, Clone, Copy, Default)]
pub struct AckTally {
    /// Acknowledgements read.
    pub read: u64,
    /// Datagrams that were not an acknowledgement under this session's key.
    pub refused: u64,
    /// The last acknowledgement read.
    pub last: Option<Ack>,
}

impl AckTally {
    /// Reads one datagram that arrived for `session`.
    pub fn read(&mut self, session: &Session, datagram: &[u8]) {
        match session.read_ack(datagram) {
            Ok(ack) => {
                self.read += 1;
                self.last = Some(ack);
            }
            Err(_) => self.refused += 1,
        }
    }

    /// In words, for the sender's closing line.
    pub fn describe(&self) -> String {
        match self.last {
            Some(ack) => {
                format!("{} acknowledgements, the last: {} accepted, {} lost", self.read, ack.accepted, ack.lost)
            }
            None => "no acknowledgement (is the receiver running, with the same key?)".into(),
        }
    }
}

/// What a replay did, as one JSON object: the `session` it sent under, the `frames` replayed,
/// the impairment's counts, the acknowledgements and the time it took (s).
pub fn replay_summary(session: u64, frames: u64, i: &Impairment, acks: &AckTally, elapsed_s: f64) -> serde_json::Value {
    serde_json::json!({
        "session": format!("{session:#018x}"),
        "frames": frames,
        "datagrams_sent": i.sent,
        "dropped": i.dropped,
        "reordered": i.reordered,
        "duplicated": i.duplicated,
        "acks": acks.read,
        "acks_refused": acks.refused,
        "last_ack": acks.last.map(|a| serde_json::json!({"accepted": a.accepted, "lost": a.lost, "highest_seq": a.highest_seq})),
        "duration_s": elapsed_s,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn a_held_datagram_follows_the_next_and_the_last_is_always_sent() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(1);
        let mut i = Impairment::new(0.0, 1.0, 0.0);
        assert!(i.pass(vec![1], false, &mut rng).is_empty(), "held back");
        assert_eq!(i.pass(vec![2], true, &mut rng), [vec![2], vec![1]]);
        assert_eq!((i.sent, i.reordered, i.dropped), (2, 1, 0));
        let mut lossy = Impairment::new(1.0 - f64::EPSILON, 0.0, 1.0);
        assert!(lossy.pass(vec![3], false, &mut rng).is_empty());
        assert_eq!(lossy.pass(vec![4], true, &mut rng), [vec![4], vec![4]]);
        assert_eq!((lossy.sent, lossy.dropped, lossy.duplicated), (2, 1, 1));
    }

    #[test]
    fn no_acknowledgement_says_what_to_check() {
        assert!(AckTally::default().describe().contains("is the receiver running"));
        let v = replay_summary(0x1f, 3, &Impairment::default(), &AckTally::default(), 1.5);
        assert_eq!((v["session"].as_str(), v["last_ack"].is_null()), (Some("0x000000000000001f"), true));
    }
}
