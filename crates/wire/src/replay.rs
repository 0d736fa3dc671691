//! The phone simulator's side of a replay (`jawtrack send`): datagrams paced out of a socket
//! ([`send_recording`], [`send_packets`]), the link impaired on purpose (datagrams dropped, held
//! back behind the next one, or sent twice, each with its probability), the receiver's
//! acknowledgements tallied, and the run summed up as JSON.

use crate::options::{BadOption, LinkError, positive, probability};
use crate::{Ack, PosePacket, Security, Session};
use jawtrack_recording::FrameRecord;
use rand::{Rng, SeedableRng};
use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

/// How a replay goes out: its pace, its length and its impairment (the `jawtrack send` flags of
/// the same names).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReplayOptions {
    /// Datagrams per second.
    pub rate: f64,
    /// Datagrams to send, cycling through the recording (`None`: each frame once).
    pub count: Option<u64>,
    /// Probability of dropping a datagram (see [`Impairment`]).
    pub loss: f64,
    /// Probability of holding a datagram back and sending it after the next one.
    pub reorder: f64,
    /// Probability of sending a datagram twice.
    pub duplicate: f64,
    /// Seed of the loss, reorder and duplicate draws.
    pub seed: u64,
}

impl Default for ReplayOptions {
    fn default() -> ReplayOptions {
        ReplayOptions { rate: 30.0, count: None, loss: 0.0, reorder: 0.0, duplicate: 0.0, seed: 1 }
    }
}

impl ReplayOptions {
    /// Refuses a probability outside [0, 1) or a rate that is not a positive number, naming the
    /// option (the probabilities first, in the order loss, reorder, duplicate).
    pub fn check(&self) -> Result<(), BadOption> {
        probability("loss", self.loss)?;
        probability("reorder", self.reorder)?;
        probability("duplicate", self.duplicate)?;
        positive("rate", self.rate, false, "a positive number of datagrams per second")?;
        Ok(())
    }

    /// The datagrams a replay of `frames` frames sends.
    pub fn datagrams(&self, frames: usize) -> u64 {
        self.count.unwrap_or(frames as u64)
    }
}

/// What a replay did: the frames sent, the session they went under, the impairment's counts,
/// the acknowledgements heard and the time it took.
#[derive(Debug, Clone)]
pub struct ReplayOutcome {
    /// Frames replayed (datagrams before the impairment).
    pub frames: u64,
    /// The session id the datagrams carried.
    pub session: u64,
    /// What the impairment did.
    pub impairment: Impairment,
    /// The receiver's acknowledgements.
    pub acks: AckTally,
    /// From the first datagram to the end of the wait for late acknowledgements (s).
    pub elapsed_s: f64,
}

impl ReplayOutcome {
    /// In words, for the sender's closing line.
    pub fn describe(&self) -> String {
        let i = &self.impairment;
        format!(
            "sent {} frames as {} datagrams in {:.1} s (session {:#018x}): dropped {}, reordered {}, duplicated {}; {}",
            self.frames,
            i.sent,
            self.elapsed_s,
            self.session,
            i.dropped,
            i.reordered,
            i.duplicated,
            self.acks.describe()
        )
    }

    /// As one JSON object ([`replay_summary`]).
    pub fn summary(&self) -> serde_json::Value {
        replay_summary(self.session, self.frames, &self.impairment, &self.acks, self.elapsed_s)
    }
}

/// Replays `frames` to `to` under a new session: [`ReplayOptions::datagrams`] datagrams at
/// `options.rate`, cycling through the frames with their frame numbers and times counting up as
/// a live session's would, impaired as the options say. `progress` hears the datagrams done so
/// far after each one.
///
/// # Examples
///
/// ```no_run
/// use jawtrack_wire::Security;
/// use jawtrack_wire::replay::{ReplayOptions, send_recording};
///
/// let frames = jawtrack_recording::open(std::path::Path::new("poses.jsonl"))?.frames;
/// let options = ReplayOptions { loss: 0.1, ..ReplayOptions::default() };
/// let outcome = send_recording(&frames, "127.0.0.1:5005".parse()?, Security::Plaintext, &options, |_| {})?;
/// println!("{}", outcome.describe());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn send_recording(
    frames: &[FrameRecord],
    to: SocketAddr,
    security: Security,
    options: &ReplayOptions,
    progress: impl FnMut(u64),
) -> Result<ReplayOutcome, LinkError> {
    if frames.is_empty() {
        return Err(LinkError::NoFrames);
    }
    let packet = |i: u64| PosePacket {
        t: i as f64 / options.rate,
        frame: i,
        ..PosePacket::from_record(&frames[(i % frames.len() as u64) as usize])
    };
    send_packets(to, security, options, options.datagrams(frames.len()), packet, progress)
}

/// Sends `datagrams` pose datagrams to `to` under a new session, the `i`th (from 0) holding
/// `packet(i)`, at `options.rate` and impaired as the options say (`options.count` is not
/// read). It reads the acknowledgements as they come, and for 300 ms after the last datagram;
/// `progress` hears the datagrams done so far after each one. A full socket buffer is waited
/// out, not counted as a loss.
///
/// # Examples
///
/// ```no_run
/// use jawtrack_wire::replay::{ReplayOptions, send_packets};
/// use jawtrack_wire::{PosePacket, Security};
///
/// let still = |i: u64| PosePacket {
///     t: i as f64 / 30.0,
///     frame: i,
///     maxilla: None,
///     mandible: None,
///     maxilla_from_mandible: None,
///     flags: 0,
/// };
/// let to = "127.0.0.1:5005".parse()?;
/// let outcome = send_packets(to, Security::Plaintext, &ReplayOptions::default(), 90, still, |_| {})?;
/// assert_eq!(outcome.impairment.sent, 90);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn send_packets(
    to: SocketAddr,
    security: Security,
    options: &ReplayOptions,
    datagrams: u64,
    mut packet: impl FnMut(u64) -> PosePacket,
    mut progress: impl FnMut(u64),
) -> Result<ReplayOutcome, LinkError> {
    options.check()?;
    let any = if to.is_ipv4() { "0.0.0.0:0" } else { "[::]:0" };
    let socket = UdpSocket::bind(any).map_err(LinkError::io("opening a UDP socket"))?;
    socket.set_nonblocking(true)?;
    let mut session = Session::new(security);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(options.seed);
    let mut impairment = Impairment::new(options.loss, options.reorder, options.duplicate);
    let mut acks = AckTally::default();
    let period = Duration::from_secs_f64(1.0 / options.rate);
    let start = Instant::now();
    let mut buf = [0u8; 2048];
    let transmit = |d: &[u8]| {
        // Loopback drops nothing; a full socket buffer is retried rather than lost.
        while let Err(e) = socket.send_to(d, to) {
            if e.kind() != std::io::ErrorKind::WouldBlock {
                return Err(LinkError::io("sending")(e));
            }
            std::thread::sleep(Duration::from_micros(200));
        }
        Ok(())
    };
    for i in 0..datagrams {
        if let Some(wait) = (start + period.mul_f64(i as f64)).checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        let datagram = session.pose_datagram(&packet(i));
        for d in impairment.pass(datagram, i + 1 == datagrams, &mut rng) {
            transmit(&d)?;
        }
        while let Ok((n, _)) = socket.recv_from(&mut buf) {
            acks.read(&session, &buf[..n]);
        }
        progress(i + 1);
    }
    // Late acknowledgements of the last datagrams.
    let until = Instant::now() + Duration::from_millis(300);
    while Instant::now() < until {
        match socket.recv_from(&mut buf) {
            Ok((n, _)) => acks.read(&session, &buf[..n]),
            Err(_) => std::thread::sleep(Duration::from_millis(10)),
        }
    }
    let elapsed_s = start.elapsed().as_secs_f64();
    Ok(ReplayOutcome { frames: datagrams, session: session.id(), impairment, acks, elapsed_s })
}

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
    fn options_out_of_range_are_refused_by_their_flag() {
        assert_eq!(ReplayOptions::default().check(), Ok(()));
        let bad = |o: ReplayOptions| o.check().map_err(|e| e.to_string()).expect_err("refused");
        let d = ReplayOptions::default();
        assert_eq!(bad(ReplayOptions { loss: 2.0, ..d }), "--loss must be a probability in [0, 1), got 2");
        assert_eq!(bad(ReplayOptions { reorder: -0.5, ..d }), "--reorder must be a probability in [0, 1), got -0.5");
        assert_eq!(bad(ReplayOptions { duplicate: 1.0, ..d }), "--duplicate must be a probability in [0, 1), got 1");
        let rate = "--rate must be a positive number of datagrams per second, got 0";
        assert_eq!(bad(ReplayOptions { rate: 0.0, ..d }), rate);
        assert!(ReplayOptions { rate: f64::NAN, ..d }.check().is_err());
        // The probabilities are named first, as `jawtrack send` always did.
        assert_eq!(bad(ReplayOptions { rate: 0.0, duplicate: 3.0, ..d }).split(' ').next(), Some("--duplicate"));
        assert_eq!((d.datagrams(7), ReplayOptions { count: Some(3), ..d }.datagrams(7)), (7, 3));
    }

    #[test]
    fn a_bad_option_or_no_frames_sends_nothing() {
        let to: SocketAddr = "127.0.0.1:9".parse().expect("address");
        let o = ReplayOptions { loss: 1.0, ..ReplayOptions::default() };
        let e = send_recording(&[], to, Security::Plaintext, &o, |_| panic!("nothing sent"));
        assert!(matches!(e, Err(LinkError::NoFrames)), "{e:?}");
        let still =
            |i| PosePacket { t: 0.0, frame: i, maxilla: None, mandible: None, maxilla_from_mandible: None, flags: 0 };
        let e = send_packets(to, Security::Plaintext, &o, 3, still, |_| panic!("nothing sent"));
        assert!(matches!(e, Err(LinkError::Option(BadOption { option: "loss", .. }))), "{e:?}");
    }

    #[test]
    fn a_replay_outcome_reads_as_the_sender_prints_it() {
        let i = Impairment { sent: 12, dropped: 1, reordered: 2, duplicated: 3, ..Impairment::default() };
        let o = ReplayOutcome { frames: 10, session: 0xab, impairment: i, acks: AckTally::default(), elapsed_s: 0.46 };
        assert_eq!(
            o.describe(),
            "sent 10 frames as 12 datagrams in 0.5 s (session 0x00000000000000ab): dropped 1, reordered 2, \
             duplicated 3; no acknowledgement (is the receiver running, with the same key?)"
        );
        assert_eq!((o.summary()["datagrams_sent"].as_u64(), o.summary()["frames"].as_u64()), (Some(12), Some(10)));
    }

    #[test]
    fn no_acknowledgement_says_what_to_check() {
        assert!(AckTally::default().describe().contains("is the receiver running"));
        let v = replay_summary(0x1f, 3, &Impairment::default(), &AckTally::default(), 1.5);
        assert_eq!((v["session"].as_str(), v["last_ack"].is_null()), (Some("0x000000000000001f"), true));
    }
}
