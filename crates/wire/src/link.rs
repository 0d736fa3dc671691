//! The receiver's accounting of a link: which datagrams to accept, and exact counts of what
//! arrived, what went missing, what came out of order and what came twice.
//!
//! Sequence numbers start at 0 in every session and rise by one per datagram, so a session's
//! losses are the numbers up to the highest seen that never arrived. A datagram below the
//! highest fills a gap (reordered) unless it was already accepted (duplicate, or a replay);
//! one further back than the window is refused as too old. The last [`LinkConfig::sessions`]
//! sessions are remembered, so replaying one of them is caught; replaying an older one is
//! caught by the freshness check on the sender's clock. Memory is bounded whatever arrives:
//! a fixed window per session and a fixed number of sessions.

use crate::{Header, WireError};

/// Limits of the accounting.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkConfig {
    /// How far behind the highest sequence number a datagram may arrive and still be accepted.
    pub window: u64,
    /// Sessions remembered (the least recently heard of is forgotten first).
    pub sessions: usize,
    /// Refuse datagrams whose sender clock is further than this from ours (ms); `None` turns
    /// the check off (for replaying old captures).
    pub max_clock_skew_ms: Option<u64>,
}

impl Default for LinkConfig {
    fn default() -> Self {
        LinkConfig { window: 1024, sessions: 16, max_clock_skew_ms: Some(60_000) }
    }
}

/// What to do with an authenticated datagram.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// New: record it. `reordered` when it arrived after a higher sequence number.
    Accept {
        /// It filled a gap.
        reordered: bool,
    },
    /// Already accepted: a duplicate or a replay; do not record it again.
    Duplicate,
    /// Refused: `stale` (sender clock too far off) or `too_old` (behind the window).
    Reject(&'static str),
}

/// Counts since the receiver started. `received = accepted + duplicated + rejected`.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Counters {
    /// Datagrams that arrived.
    pub received: u64,
    /// Accepted (each sequence number of a session at most once).
    pub accepted: u64,
    /// Sequence numbers missing (up to each session's highest).
    pub lost: u64,
    /// Accepted after a higher sequence number.
    pub reordered: u64,
    /// Already accepted before.
    pub duplicated: u64,
    /// Refused, by reason (`length`, `magic`, `version`, `kind`, `header`, `security`,
    /// `authentication`, `malformed`, `stale`, `too_old`, `not_a_pose`).
    pub rejected: std::collections::BTreeMap<&'static str, u64>,
}

impl Counters {
    /// All rejections.
    pub fn rejected_total(&self) -> u64 {
        self.rejected.values().sum()
    }

    /// The counts in words, as the receiver prints them while it runs and when it stops.
    pub fn describe(&self) -> String {
        format!(
            "received {}, accepted {}, lost {}, reordered {}, duplicated {}, rejected {}",
            self.received,
            self.accepted,
            self.lost,
            self.reordered,
            self.duplicated,
            self.rejected_total()
        )
    }

    /// The counts as JSON: the receiver's exit summary and the viewer's status share them.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "received": self.received,
            "accepted": self.accepted,
            "lost": self.lost,
            "reordered": self.reordered,
            "duplicated": self.duplicated,
            "rejected": self.rejected_total(),
            "rejected_by_reason": self.rejected,
        })
    }
}

#[derive(Debug)]
struct SessionState {
    id: u64,
    highest: u64,
    accepted: u64,
    /// `ring[s % window] == s` iff sequence `s` (within the window) was accepted.
    ring: Vec<u64>,
    last_heard: u64,
}

impl SessionState {
    fn lost(&self) -> u64 {
        // At least one datagram (the first) is accepted, and never more than highest + 1.
        self.highest - (self.accepted - 1)
    }
}

/// A session as the receiver sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SessionCounts {
    /// The session id.
    pub session: u64,
    /// Highest sequence number accepted.
    pub highest_seq: u64,
    /// Datagrams accepted.
    pub accepted: u64,
    /// Sequence numbers missing up to the highest.
    pub lost: u64,
}

/// The accounting of every datagram that reached the receiver.
#[derive(Debug)]
pub struct Link {
    config: LinkConfig,
    sessions: Vec<SessionState>,
    counters: Counters,
    /// Losses of sessions already forgotten.
    lost_forgotten: u64,
    tick: u64,
}

impl Link {
    /// An empty account.
    pub fn new(config: LinkConfig) -> Link {
        let config = LinkConfig { window: config.window.max(1), sessions: config.sessions.max(1), ..config };
        Link { config, sessions: Vec::new(), counters: Counters::default(), lost_forgotten: 0, tick: 0 }
    }

    /// Counts a datagram that failed to decode.
    pub fn reject(&mut self, error: &WireError) {
        self.count_rejection(error.kind_name());
    }

    /// Counts a datagram refused for another reason (e.g. `not_a_pose`).
    pub fn count_rejection(&mut self, reason: &'static str) {
        self.counters.received += 1;
        *self.counters.rejected.entry(reason).or_default() += 1;
    }

    /// Judges an authenticated datagram's header, at our wall clock `now_unix_ms`.
    pub fn check(&mut self, h: &Header, now_unix_ms: u64) -> Verdict {
        if let Some(skew) = self.config.max_clock_skew_ms
            && h.sent_unix_ms.abs_diff(now_unix_ms) > skew
        {
            self.count_rejection("stale");
            return Verdict::Reject("stale");
        }
        self.tick += 1;
        let window = self.config.window;
        let index = match self.sessions.iter().position(|s| s.id == h.session) {
            Some(i) => i,
            None => {
                if self.sessions.len() == self.config.sessions
                    && let Some(oldest) = (0..self.sessions.len()).min_by_key(|&i| self.sessions[i].last_heard)
                {
                    let gone = self.sessions.swap_remove(oldest);
                    self.lost_forgotten += gone.lost();
                }
                // A new session starts at the sequence number before 0: nothing accepted yet.
                self.sessions.push(SessionState {
                    id: h.session,
                    highest: 0,
                    accepted: 0,
                    ring: vec![u64::MAX; window as usize],
                    last_heard: self.tick,
                });
                let s = self.sessions.len() - 1;
                return self.accept_first(s, h.seq);
            }
        };
        let s = &mut self.sessions[index];
        s.last_heard = self.tick;
        let slot = (h.seq % window) as usize;
        let verdict = if h.seq > s.highest {
            s.highest = h.seq;
            Verdict::Accept { reordered: false }
        } else if s.highest - h.seq >= window {
            Verdict::Reject("too_old")
        } else if s.ring[slot] == h.seq {
            Verdict::Duplicate
        } else {
            Verdict::Accept { reordered: true }
        };
        match verdict {
            Verdict::Accept { reordered } => {
                s.ring[slot] = h.seq;
                s.accepted += 1;
                self.counters.received += 1;
                self.counters.accepted += 1;
                self.counters.reordered += u64::from(reordered);
            }
            Verdict::Duplicate => {
                self.counters.received += 1;
                self.counters.duplicated += 1;
            }
            Verdict::Reject(reason) => self.count_rejection(reason),
        }
        verdict
    }

    fn accept_first(&mut self, index: usize, seq: u64) -> Verdict {
        let window = self.config.window;
        let s = &mut self.sessions[index];
        s.highest = seq;
        s.ring[(seq % window) as usize] = seq;
        s.accepted = 1;
        self.counters.received += 1;
        self.counters.accepted += 1;
        Verdict::Accept { reordered: false }
    }

    /// The counts so far, with the losses of every session.
    pub fn counters(&self) -> Counters {
        let mut c = self.counters.clone();
        c.lost = self.lost_forgotten + self.sessions.iter().map(SessionState::lost).sum::<u64>();
        c
    }

    /// One session's counts, if it is remembered.
    pub fn session(&self, id: u64) -> Option<SessionCounts> {
        self.sessions.iter().find(|s| s.id == id).map(|s| SessionCounts {
            session: s.id,
            highest_seq: s.highest,
            accepted: s.accepted,
            lost: s.lost(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Kind;

    fn h(session: u64, seq: u64) -> Header {
        Header { kind: Kind::Pose, session, seq, sent_unix_ms: 1000 }
    }

    #[test]
    fn gaps_reordering_and_duplicates_are_counted_exactly() {
        let mut link = Link::new(LinkConfig::default());
        // 0, 1, 3, 2 (reordered), 2 (duplicate), 6 (4 and 5 lost), 5 (late).
        let verdicts: Vec<Verdict> = [0, 1, 3, 2, 2, 6, 5].iter().map(|&s| link.check(&h(1, s), 1000)).collect();
        assert_eq!(verdicts[3], Verdict::Accept { reordered: true });
        assert_eq!(verdicts[4], Verdict::Duplicate);
        let c = link.counters();
        assert_eq!((c.received, c.accepted, c.lost, c.reordered, c.duplicated), (7, 6, 1, 2, 1));
        assert_eq!(link.session(1).map(|s| (s.highest_seq, s.lost)), Some((6, 1)));
    }

    #[test]
    fn a_session_that_starts_late_counts_its_first_numbers_lost() {
        let mut link = Link::new(LinkConfig::default());
        link.check(&h(1, 3), 1000);
        assert_eq!(link.counters().lost, 3);
    }

    #[test]
    fn replays_behind_the_window_and_off_the_clock_are_refused() {
        let mut link = Link::new(LinkConfig { window: 4, ..LinkConfig::default() });
        for s in 0..10 {
            link.check(&h(1, s), 1000);
        }
        assert_eq!(link.check(&h(1, 2), 1000), Verdict::Reject("too_old"));
        assert_eq!(link.check(&h(1, 8), 1000), Verdict::Duplicate);
        assert_eq!(link.check(&h(2, 0), 1000 + 61_000), Verdict::Reject("stale"));
        let c = link.counters();
        assert_eq!(c.received, c.accepted + c.duplicated + c.rejected_total());
        assert_eq!(c.accepted, 10);
    }

    #[test]
    fn memory_stays_bounded_and_forgotten_sessions_keep_their_losses() {
        let mut link = Link::new(LinkConfig { sessions: 3, ..LinkConfig::default() });
        for session in 0..100 {
            link.check(&h(session, 1), 1000);
        }
        assert_eq!(link.sessions.len(), 3);
        assert_eq!(link.counters().lost, 100, "each session missed its datagram 0");
    }
}
