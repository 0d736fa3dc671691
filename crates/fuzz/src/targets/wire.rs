//! The link's datagrams as the receiver and the phone read them: pose datagrams (sealed under
//! the pairing key, and in development plaintext, where a mutant gets past authentication to
//! the body's parser) and acknowledgements. A datagram that decodes must encode back to one
//! that decodes to the same message.

use crate::run::Verdict;
use crate::targets::files::refused;
use jawtrack_wire::{Key, Message, Security, Session, decode, encode_ack, encode_pose};

/// The golden vectors' key (fixtures/wire/golden.json).
fn key() -> Key {
    Key::from_bytes(std::array::from_fn(|i| i as u8))
}

fn golden(kind: &str) -> Vec<Vec<u8>> {
    let file = crate::targets::fixtures().join("wire/golden.json");
    let Ok(text) = std::fs::read_to_string(file) else { return vec![] };
    let Ok(json) = serde_json::from_str::<serde_json::Value>(&text) else { return vec![] };
    let vectors = json["vectors"].as_array().cloned().unwrap_or_default();
    vectors
        .iter()
        .filter_map(|v| v["hex"].as_str())
        .filter_map(|h| (0..h.len()).step_by(2).map(|i| u8::from_str_radix(h.get(i..i + 2)?, 16).ok()).collect())
        .filter(|d: &Vec<u8>| d.get(5) == Some(&if kind == "pose" { 1 } else { 2 }))
        .collect()
}

/// The golden datagrams of `kind`, and each again in plaintext.
fn seeds_of(kind: &str) -> Vec<Vec<u8>> {
    let mut seeds = golden(kind);
    let plain: Vec<Vec<u8>> = seeds
        .iter()
        .filter_map(|d| decode(d, &Security::Sealed(key())).ok())
        .map(|m| encode(&m, &Security::Plaintext))
        .collect();
    seeds.extend(plain);
    seeds
}

pub fn pose_seeds() -> Vec<Vec<u8>> {
    seeds_of("pose")
}

pub fn ack_seeds() -> Vec<Vec<u8>> {
    seeds_of("ack")
}

pub fn datagram(input: &[u8]) -> Result<Verdict, String> {
    let mut verdict = Verdict::Refused;
    for security in [Security::Sealed(key()), Security::Plaintext] {
        let message = match decode(input, &security) {
            Ok(m) => m,
            Err(e) => {
                refused(e)?;
                continue;
            }
        };
        let again = encode(&message, &security);
        let back = decode(&again, &security).map_err(|e| format!("its own encoding does not decode: {e}"))?;
        // Compared as plaintext bytes: a NaN a datagram carries is equal to itself there.
        if encode(&back, &Security::Plaintext) != encode(&message, &Security::Plaintext) {
            return Err("encoded and decoded, the message changed".into());
        }
        verdict = Verdict::Accepted;
    }
    Ok(verdict)
}

/// The datagram of `message`, with its own header fields.
fn encode(message: &Message, security: &Security) -> Vec<u8> {
    match message {
        Message::Pose(h, p) => encode_pose((h.session, h.seq, h.sent_unix_ms), p, security),
        Message::Ack(h, a) => encode_ack((h.session, h.seq, h.sent_unix_ms), a, security),
    }
}

pub fn ack(input: &[u8]) -> Result<Verdict, String> {
    // The phone's side: a session reads acknowledgements of itself only.
    for security in [Security::Sealed(key()), Security::Plaintext] {
        if let Err(e) = Session::new(security).read_ack(input) {
            refused(e)?;
        }
    }
    datagram(input)
}
