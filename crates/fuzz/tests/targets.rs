//! Every target starts from seeds it accepts, and survives a short run; the runner catches a
//! planted panic, hang and broken invariant, saving the input that did it.

use jawtrack_fuzz::run::{Options, Verdict, fuzz, replay};
use jawtrack_fuzz::targets;
use std::process::Command;
use std::time::Duration;

#[test]
fn every_target_accepts_its_seeds_and_survives_a_short_run() {
    let all = targets::all();
    let mut checked = Vec::new();
    for target in &all {
        let seeds = (target.seeds)();
        assert!(!seeds.is_empty(), "{}: no seeds (are fixtures/ and harness-cad/ there?)", target.name);
        for (k, seed) in seeds.iter().enumerate() {
            assert_eq!(
                replay(target, seed).map_err(|p| format!("{p:?}")),
                Ok(Verdict::Accepted),
                "{} seed {k}",
                target.name
            );
        }
        let options = Options { runs: 300, seed: 42, time_limit: Duration::from_secs(10) };
        let hang = Box::new(|_: &[u8], index: u64, _| panic!("input {index} hung"));
        let tally = fuzz(target, &options, hang, |_| {}).unwrap_or_else(|f| panic!("{}: {f:?}", target.name));
        assert_eq!(tally.inputs, 300, "{}", target.name);
        // Mutants must reach past the syntax: some are accepted, and some refused.
        assert!(
            tally.accepted > seeds.len() as u64 && tally.accepted < 300,
            "{}: {} accepted",
            target.name,
            tally.accepted
        );
        checked.push(target.name);
    }
    assert_eq!(checked.len(), 13, "{checked:?}");
}

#[test]
fn the_runner_stops_on_a_planted_panic_hang_or_broken_invariant_and_saves_the_input() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut checked = 0;
    for (kind, said) in
        [("panic", "PANIC: a planted panic"), ("hang", "HANG"), ("invariant", "BROKEN INVARIANT: a planted")]
    {
        let out = Command::new(env!("CARGO_BIN_EXE_jawtrack-fuzz"))
            .args(["--self-test", kind, "--runs", "1000", "--time-limit-ms", "300", "--failures"])
            .arg(dir.path())
            .output()
            .expect("the runner runs");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{kind}: {err}");
        assert!(err.contains(said) && err.contains("--replay"), "{kind}: {err}");
        let saved = std::fs::read_dir(dir.path()).expect("the failures folder").count();
        checked += 1;
        assert_eq!(saved, checked, "{kind}: one saved input per failure");
    }
    assert_eq!(checked, 3);
}

#[test]
fn an_unknown_target_is_named_and_the_list_names_every_target() {
    let out = Command::new(env!("CARGO_BIN_EXE_jawtrack-fuzz")).arg("nosuch").output().expect("runs");
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no target named `nosuch`: `jawtrack-fuzz --list`"));
    let list = Command::new(env!("CARGO_BIN_EXE_jawtrack-fuzz")).arg("--list").output().expect("runs");
    let list = String::from_utf8_lossy(&list.stdout);
    for target in targets::all() {
        assert!(list.lines().any(|l| l.starts_with(target.name)), "{} not listed:\n{list}", target.name);
    }
}
