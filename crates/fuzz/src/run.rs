//! The runner: mutates a target's seeds, feeds each mutant to the target under
//! `catch_unwind`, and stops at the first panic, broken invariant or input that runs past
//! the time limit, with that input saved. Mutants a target accepts join the pool mutated
//! further (up to [`POOL`]), so valid-but-odd files breed more of their kind: the only
//! feedback a runner without coverage instrumentation has.

use crate::mutate::{Shape, mutate};
use rand::seq::IndexedRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Accepted mutants kept to mutate further.
pub const POOL: usize = 256;

/// What a target made of an input.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// A value came back, and its invariants held.
    Accepted,
    /// A clear error came back.
    Refused,
}

/// Feeds one input to a target: `Err` is a broken invariant, named.
pub type Run = fn(&[u8]) -> Result<Verdict, String>;

/// A parser or door under test.
pub struct Target {
    /// Its name on the command line.
    pub name: &'static str,
    /// What it feeds, and to what.
    pub about: &'static str,
    /// The input's structure, for the mutators.
    pub shape: Shape,
    /// Mutants are cut to this length (bytes).
    pub max_len: usize,
    /// Valid inputs to start from.
    pub seeds: fn() -> Vec<Vec<u8>>,
    /// Feeds one input: `Err` is a broken invariant, named.
    pub run: Run,
    /// What else a run should report (the C door: how many calls it made).
    pub note: Option<fn() -> String>,
}

/// How a run went.
#[derive(Debug, Clone, Default)]
pub struct Tally {
    /// Inputs fed, seeds included.
    pub inputs: u64,
    /// Of them, accepted.
    pub accepted: u64,
    /// Slowest input (s).
    pub slowest_s: f64,
    /// Wall time (s).
    pub elapsed_s: f64,
}

/// Why a run stopped early.
#[derive(Debug, Clone)]
pub enum Problem {
    /// The target panicked.
    Panic(String),
    /// The target's invariant broke.
    Invariant(String),
}

/// The input that stopped a run.
#[derive(Debug, Clone)]
pub struct Found {
    /// What went wrong.
    pub problem: Problem,
    /// Its index in the run (0 is the first seed).
    pub input_index: u64,
    /// The input.
    pub input: Vec<u8>,
}

/// A run's settings.
#[derive(Debug, Clone)]
pub struct Options {
    /// Inputs to feed, seeds included.
    pub runs: u64,
    /// The random seed: the same seed and runs give the same inputs.
    pub seed: u64,
    /// An input that runs longer than this is a hang.
    pub time_limit: Duration,
}

/// Called from the watchdog thread when an input runs past the limit: it gets the input and
/// how long it has run, and must end the process (the stuck thread cannot be stopped).
pub type OnHang = Box<dyn Fn(&[u8], u64, Duration) + Send>;

/// Feeds `options.runs` inputs to `target`: its seeds first, then mutants.
pub fn fuzz(
    target: &Target,
    options: &Options,
    on_hang: OnHang,
    mut progress: impl FnMut(&Tally),
) -> Result<Tally, Found> {
    let seeds = (target.seeds)();
    let mut pool: Vec<Vec<u8>> = Vec::new();
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    let watch = Watchdog::start(options.time_limit, on_hang);
    let start = Instant::now();
    let mut tally = Tally::default();
    let mut input = Vec::new();
    for index in 0..options.runs {
        input.clear();
        if let Some(seed) = seeds.get(index as usize) {
            input.extend_from_slice(seed);
        } else {
            let parent =
                if !pool.is_empty() && rng.random_bool(0.5) { pool.choose(&mut rng) } else { seeds.choose(&mut rng) };
            input.extend_from_slice(parent.map_or(&[][..], Vec::as_slice));
            mutate(&mut rng, &mut input, target.shape, &seeds, target.max_len);
        }
        watch.arm(index, &input);
        let began = Instant::now();
        let outcome = catch_unwind(AssertUnwindSafe(|| (target.run)(&input)));
        watch.disarm();
        tally.slowest_s = tally.slowest_s.max(began.elapsed().as_secs_f64());
        tally.inputs += 1;
        let problem = match outcome {
            Ok(Ok(Verdict::Accepted)) => {
                tally.accepted += 1;
                if index as usize >= seeds.len() {
                    remember(&mut rng, &mut pool, &input);
                }
                None
            }
            Ok(Ok(Verdict::Refused)) => None,
            Ok(Err(why)) => Some(Problem::Invariant(why)),
            Err(_) => Some(Problem::Panic(take_panic_message())),
        };
        if let Some(problem) = problem {
            return Err(Found { problem, input_index: index, input });
        }
        if index % 1024 == 0 {
            tally.elapsed_s = start.elapsed().as_secs_f64();
            progress(&tally);
        }
    }
    tally.elapsed_s = start.elapsed().as_secs_f64();
    Ok(tally)
}

/// Feeds one input (a saved failure, say) and says what happened.
pub fn replay(target: &Target, input: &[u8]) -> Result<Verdict, Problem> {
    match catch_unwind(AssertUnwindSafe(|| (target.run)(input))) {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(why)) => Err(Problem::Invariant(why)),
        Err(_) => Err(Problem::Panic(take_panic_message())),
    }
}

fn remember(rng: &mut impl Rng, pool: &mut Vec<Vec<u8>>, input: &[u8]) {
    if pool.len() < POOL {
        pool.push(input.to_vec());
    } else {
        let k = rng.random_range(0..POOL);
        pool[k].clear();
        pool[k].extend_from_slice(input);
    }
}

static PANIC_MESSAGE: Mutex<Option<String>> = Mutex::new(None);

/// Replaces the panic hook with one that keeps the message and its place for the report, and
/// prints nothing: a target may panic (and be caught) inside a door that turns panics into
/// errors, and the runner judges that itself.
pub fn quiet_panics() {
    std::panic::set_hook(Box::new(|info| {
        let message = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| (*s).to_owned())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "(no message)".into());
        let place = info.location().map(|l| format!(" at {}:{}", l.file(), l.line())).unwrap_or_default();
        if let Ok(mut slot) = PANIC_MESSAGE.lock() {
            *slot = Some(format!("{message}{place}"));
        }
    }));
}

/// The message of the last panic the hook saw, if any since the last call.
pub fn take_panic_message() -> String {
    PANIC_MESSAGE.lock().ok().and_then(|mut m| m.take()).unwrap_or_else(|| "a panic (message not kept)".into())
}

/// Watches the input in flight from another thread.
struct Watchdog {
    state: Arc<WatchState>,
}

struct WatchState {
    armed: AtomicBool,
    started_ms: AtomicU64,
    index: AtomicU64,
    input: Mutex<Vec<u8>>,
    clock: Instant,
}

impl Watchdog {
    fn start(limit: Duration, on_hang: OnHang) -> Watchdog {
        let state = Arc::new(WatchState {
            armed: AtomicBool::new(false),
            started_ms: AtomicU64::new(0),
            index: AtomicU64::new(0),
            input: Mutex::new(Vec::new()),
            clock: Instant::now(),
        });
        let watched = Arc::clone(&state);
        let poll = (limit / 10).clamp(Duration::from_millis(5), Duration::from_millis(100));
        // Detached: it dies with the process; a run that ends leaves it asleep.
        std::thread::spawn(move || {
            loop {
                std::thread::sleep(poll);
                if !watched.armed.load(Ordering::Acquire) {
                    continue;
                }
                let now = watched.clock.elapsed().as_millis() as u64;
                let ran = Duration::from_millis(now.saturating_sub(watched.started_ms.load(Ordering::Acquire)));
                if ran > limit && watched.armed.load(Ordering::Acquire) {
                    let input = watched.input.lock().map(|i| i.clone()).unwrap_or_default();
                    on_hang(&input, watched.index.load(Ordering::Acquire), ran);
                    return;
                }
            }
        });
        Watchdog { state }
    }

    fn arm(&self, index: u64, input: &[u8]) {
        if let Ok(mut slot) = self.state.input.lock() {
            slot.clear();
            slot.extend_from_slice(input);
        }
        self.state.index.store(index, Ordering::Release);
        self.state.started_ms.store(self.state.clock.elapsed().as_millis() as u64, Ordering::Release);
        self.state.armed.store(true, Ordering::Release);
    }

    fn disarm(&self) {
        self.state.armed.store(false, Ordering::Release);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seeds() -> Vec<Vec<u8>> {
        vec![b"[1, 2, 3]".to_vec()]
    }

    fn options(runs: u64) -> Options {
        Options { runs, seed: 1, time_limit: Duration::from_secs(5) }
    }

    fn never_hangs() -> OnHang {
        Box::new(|_, index, _| panic!("input {index} was reported hung"))
    }

    #[test]
    fn a_run_feeds_every_input_and_counts_what_was_accepted() {
        let target = Target {
            name: "json",
            about: "",
            shape: Shape::Json,
            max_len: 100,
            seeds,
            note: None,
            run: |d| {
                Ok(if serde_json::from_slice::<serde_json::Value>(d).is_ok() {
                    Verdict::Accepted
                } else {
                    Verdict::Refused
                })
            },
        };
        let tally = fuzz(&target, &options(2000), never_hangs(), |_| {}).expect("nothing to find");
        assert_eq!(tally.inputs, 2000);
        assert!(tally.accepted > 200 && tally.accepted < 2000, "{} accepted", tally.accepted);
    }

    #[test]
    fn a_panic_stops_the_run_with_its_message_and_input() {
        quiet_panics();
        let target = Target {
            name: "picky",
            about: "",
            shape: Shape::Binary,
            max_len: 100,
            seeds,
            note: None,
            run: |d| if d.contains(&b'!') { panic!("an exclamation mark") } else { Ok(Verdict::Refused) },
        };
        let found = fuzz(&target, &options(1_000_000), never_hangs(), |_| {}).expect_err("the mutator writes a '!'");
        let Problem::Panic(message) = &found.problem else { panic!("{:?}", found.problem) };
        assert!(message.contains("an exclamation mark") && message.contains("run.rs"), "{message}");
        assert!(found.input.contains(&b'!') && found.input_index > 0);
        assert!(replay(&target, &found.input).is_err(), "the saved input fails again");
    }

    #[test]
    fn a_broken_invariant_stops_the_run() {
        let target = Target {
            name: "short",
            about: "",
            shape: Shape::Binary,
            max_len: 100,
            seeds,
            note: None,
            run: |d| if d.len() > 20 { Err(format!("{} bytes", d.len())) } else { Ok(Verdict::Accepted) },
        };
        let found = fuzz(&target, &options(1_000_000), never_hangs(), |_| {}).expect_err("mutants grow");
        assert!(matches!(&found.problem, Problem::Invariant(w) if w.ends_with("bytes")), "{:?}", found.problem);
    }

    #[test]
    fn the_watchdog_reports_an_input_that_runs_past_the_limit() {
        let (tx, rx) = std::sync::mpsc::channel();
        let tx = Mutex::new(tx);
        let on_hang: OnHang = Box::new(move |input, index, ran| {
            let _ = tx.lock().expect("the sender").send((input.to_vec(), index, ran));
        });
        let target = Target {
            name: "slow",
            about: "",
            shape: Shape::Binary,
            max_len: 100,
            seeds,
            note: None,
            run: |_| {
                std::thread::sleep(Duration::from_millis(400));
                Ok(Verdict::Refused)
            },
        };
        let limited = Options { runs: 1, seed: 1, time_limit: Duration::from_millis(100) };
        fuzz(&target, &limited, on_hang, |_| {}).expect("the target itself returns");
        let (input, index, ran) = rx.recv_timeout(Duration::from_secs(5)).expect("a hang report");
        assert_eq!((input.as_slice(), index), (&b"[1, 2, 3]"[..], 0));
        assert!(ran > Duration::from_millis(100), "{ran:?}");
    }
}
