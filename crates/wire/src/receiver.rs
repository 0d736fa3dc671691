//! A receiver's handling of each datagram: decoded, judged by the [`Link`] accounting, turned
//! into a recording line when accepted, and answered with an acknowledgement at most ten times
//! a second per phone (enough for the app's link light); and the socket loop around it
//! ([`receive`]), which hands what is not the link's business to a [`ReceiveSink`].

use crate::link::{Counters, Link, LinkConfig, Verdict};
use crate::options::{BadOption, LinkError, positive};
use crate::{Ack, Message, Security, decode, encode_ack, unix_ms};
use jawtrack_recording::{FrameRecord, RecordingHeader};
use std::io::ErrorKind;
use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// The shortest time between two acknowledgements to the same phone.
pub const ACK_INTERVAL: Duration = Duration::from_millis(100);

/// How often [`ReceiveSink::live`] hears the counters.
pub const LIVE_INTERVAL: Duration = Duration::from_millis(500);

/// The socket's read timeout in [`receive`]: the longest one pass waits for a datagram, so the
/// stop flag, the time limits and [`ReceiveSink::poll`] are seen to at least this often.
pub const POLL_INTERVAL: Duration = Duration::from_millis(100);

/// How a receiver runs (the `jawtrack receive` flags of the same names) and how often it
/// reports.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReceiveOptions {
    /// Refuse datagrams whose sender clock is further than this from ours (s); 0 turns the
    /// check off.
    pub max_clock_skew: f64,
    /// Stop after this many seconds (`None`: when the stop flag is set).
    pub duration: Option<f64>,
    /// Stop once nothing has arrived for this many seconds after the first datagram.
    pub idle_exit: Option<f64>,
    /// How often [`ReceiveSink::report`] hears the counters.
    pub report_every: Duration,
}

impl Default for ReceiveOptions {
    fn default() -> ReceiveOptions {
        ReceiveOptions { max_clock_skew: 60.0, duration: None, idle_exit: None, report_every: Duration::from_secs(10) }
    }
}

impl ReceiveOptions {
    /// Refuses times that cannot be, naming the option: a clock skew that is not a number of
    /// seconds ≥ 0, a duration or idle time that is not a positive one.
    pub fn check(&self) -> Result<(), BadOption> {
        positive("max-clock-skew", self.max_clock_skew, true, "a number of seconds ≥ 0")?;
        for (option, v) in [("duration", self.duration), ("idle-exit", self.idle_exit)] {
            if let Some(v) = v {
                positive(option, v, false, "a positive number of seconds")?;
            }
        }
        Ok(())
    }

    /// The accounting's limits: the default ones, with this clock skew (ms; none for 0).
    pub fn link_config(&self) -> LinkConfig {
        let max_clock_skew_ms = (self.max_clock_skew > 0.0).then_some((self.max_clock_skew * 1e3) as u64);
        LinkConfig { max_clock_skew_ms, ..LinkConfig::default() }
    }
}

/// What a receiver does with what the link gives, beside the accounting: record the accepted
/// frames, show them, tell the operator how it goes. Only [`ReceiveSink::frame`] is required.
pub trait ReceiveSink {
    /// What the sink's own work fails with; a socket error of the loop becomes one too.
    type Error: From<LinkError>;

    /// An accepted frame and its sequence number, in arrival order.
    fn frame(&mut self, record: &FrameRecord, seq: u64) -> Result<(), Self::Error>;

    /// Once every pass of the loop (at least every [`POLL_INTERVAL`]): work that comes from
    /// outside the link, such as a bite the live viewer accepted.
    fn poll(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }

    /// Every [`LIVE_INTERVAL`]: the counters so far and when the last datagram arrived.
    fn live(&mut self, _counters: &Counters, _last_arrival: Option<Instant>) {}

    /// Every [`ReceiveOptions::report_every`]: the counters so far.
    fn report(&mut self, _counters: &Counters) {}
}

/// What a receiver run did.
#[derive(Debug, Clone)]
pub struct ReceiveOutcome {
    /// The counts of the whole run.
    pub counters: Counters,
    /// Acknowledgements sent.
    pub acks_sent: u64,
    /// The run's length (s).
    pub elapsed_s: f64,
}

impl ReceiveOutcome {
    /// As one JSON object ([`run_summary`]), with the CPU time the run took (s, when known).
    pub fn summary(&self, cpu_s: Option<f64>) -> serde_json::Value {
        run_summary(&self.counters, self.acks_sent, self.elapsed_s, cpu_s)
    }
}

/// Receives on `socket` (bound already; its read timeout becomes [`POLL_INTERVAL`]) until
/// `stop` is set or a time limit of `options` passes: every datagram is judged under
/// `security`, every accepted frame goes to `sink`, and each phone is acknowledged (a phone
/// that went away is not an error). Only a socket that fails for good, or the sink, ends it
/// with an error.
///
/// # Examples
///
/// ```no_run
/// use jawtrack_recording::FrameRecord;
/// use jawtrack_wire::Security;
/// use jawtrack_wire::options::LinkError;
/// use jawtrack_wire::receiver::{ReceiveOptions, ReceiveSink, receive};
///
/// struct Print;
/// impl ReceiveSink for Print {
///     type Error = LinkError;
///     fn frame(&mut self, record: &FrameRecord, seq: u64) -> Result<(), LinkError> {
///         println!("{seq}: frame {} at {} s", record.frame, record.t);
///         Ok(())
///     }
/// }
///
/// let socket = std::net::UdpSocket::bind("0.0.0.0:5005")?;
/// let options = ReceiveOptions { duration: Some(60.0), ..ReceiveOptions::default() };
/// let stop = std::sync::atomic::AtomicBool::new(false);
/// let outcome = receive(&socket, Security::Plaintext, &options, &stop, &mut Print)?;
/// println!("{}", outcome.counters.describe());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn receive<S: ReceiveSink>(
    socket: &UdpSocket,
    security: Security,
    options: &ReceiveOptions,
    stop: &AtomicBool,
    sink: &mut S,
) -> Result<ReceiveOutcome, S::Error> {
    options.check().map_err(LinkError::from)?;
    socket.set_read_timeout(Some(POLL_INTERVAL)).map_err(LinkError::from)?;
    let mut receiver = Receiver::new(options.link_config(), security, rand::random());
    let started = Instant::now();
    let (mut last_report, mut last_live, mut last_arrival) = (started, started, None::<Instant>);
    // Longer than any datagram, so an oversized one shows as a wrong length, not a cut one.
    let mut buf = [0u8; 2048];
    while !stop.load(Ordering::SeqCst) {
        if options.duration.is_some_and(|d| started.elapsed().as_secs_f64() >= d)
            || options.idle_exit.zip(last_arrival).is_some_and(|(idle, t)| t.elapsed().as_secs_f64() >= idle)
        {
            break;
        }
        // Every pass: the socket's read timeout keeps passes short when no datagram comes.
        sink.poll()?;
        if last_live.elapsed() >= LIVE_INTERVAL {
            last_live = Instant::now();
            sink.live(&receiver.link().counters(), last_arrival);
        }
        if last_report.elapsed() >= options.report_every {
            last_report = Instant::now();
            sink.report(&receiver.link().counters());
        }
        let (n, from) = match socket.recv_from(&mut buf) {
            Ok(x) => x,
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut | ErrorKind::Interrupted) => {
                continue;
            }
            // ICMP errors from earlier acknowledgements (the phone went away) surface here.
            Err(e) if e.kind() == ErrorKind::ConnectionRefused => continue,
            Err(e) => return Err(LinkError::io("receiving")(e).into()),
        };
        let now = Instant::now();
        last_arrival = Some(now);
        let got = receiver.datagram(&buf[..n], from, unix_ms(), now);
        if let Some((record, seq)) = got.frame {
            sink.frame(&record, seq)?;
        }
        // A phone that vanished is not an error for the receiver.
        if let Some(ack) = got.ack
            && socket.send_to(&ack, from).is_ok()
        {
            receiver.ack_sent(from, now);
        }
    }
    let elapsed_s = started.elapsed().as_secs_f64();
    Ok(ReceiveOutcome { counters: receiver.link().counters(), acks_sent: receiver.acks_sent(), elapsed_s })
}

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
    fn times_that_cannot_be_are_refused_by_their_flag() {
        let d = ReceiveOptions::default();
        assert_eq!(d.check(), Ok(()));
        let bad = |o: ReceiveOptions| o.check().map_err(|e| e.to_string()).expect_err("refused");
        let skew = "--max-clock-skew must be a number of seconds ≥ 0, got -1";
        assert_eq!(bad(ReceiveOptions { max_clock_skew: -1.0, ..d }), skew);
        let duration = "--duration must be a positive number of seconds, got 0";
        assert_eq!(bad(ReceiveOptions { duration: Some(0.0), ..d }), duration);
        let idle = "--idle-exit must be a positive number of seconds, got inf";
        assert_eq!(bad(ReceiveOptions { idle_exit: Some(f64::INFINITY), ..d }), idle);
        assert_eq!(ReceiveOptions { max_clock_skew: 0.0, ..d }.link_config().max_clock_skew_ms, None);
        assert_eq!(ReceiveOptions { max_clock_skew: 1.5, ..d }.link_config().max_clock_skew_ms, Some(1500));
    }

    /// Counts what it is given.
    #[derive(Default)]
    struct Count {
        frames: u64,
        polls: u64,
    }

    impl ReceiveSink for Count {
        type Error = LinkError;
        fn frame(&mut self, _: &FrameRecord, _: u64) -> Result<(), LinkError> {
            self.frames += 1;
            Ok(())
        }
        fn poll(&mut self) -> Result<(), LinkError> {
            self.polls += 1;
            Ok(())
        }
    }

    #[test]
    fn a_receiver_stops_on_its_flag_or_its_time_limit() {
        let socket = UdpSocket::bind("127.0.0.1:0").expect("socket");
        let mut sink = Count::default();
        let o = receive(&socket, Security::Plaintext, &ReceiveOptions::default(), &AtomicBool::new(true), &mut sink);
        assert_eq!((o.expect("stopped").counters, sink.polls), (Counters::default(), 0));
        let once = ReceiveOptions { duration: Some(0.05), ..ReceiveOptions::default() };
        let o = receive(&socket, Security::Plaintext, &once, &AtomicBool::new(false), &mut sink).expect("ran");
        assert!(o.elapsed_s >= 0.05 && sink.polls >= 1 && sink.frames == 0, "{o:?}");
        let never = ReceiveOptions { idle_exit: Some(-1.0), ..ReceiveOptions::default() };
        let e = receive(&socket, Security::Plaintext, &never, &AtomicBool::new(false), &mut sink);
        assert_eq!(
            e.map_err(|e| e.to_string()).expect_err("refused"),
            "--idle-exit must be a positive number of seconds, got -1"
        );
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
