//! Golden datagrams (`fixtures/wire/golden.json`): the exact bytes this version puts on the
//! wire for given fields, so that another implementation (or a later version of this one) can
//! be checked against them. Regenerate only on purpose, with `JAWTRACK_BLESS=1`, and say why
//! in the commit: a changed datagram breaks every phone in the field.

use jawtrack_pose::Pose;
use jawtrack_wire::{Ack, Key, Message, PacketBody, PosePacket, Security, decode, encode_ack, encode_pose};
use nalgebra::Vector3;
use serde_json::{Value, json};

const FILE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/wire/golden.json");

fn key() -> Key {
    "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f".parse().expect("hex key")
}

fn packet() -> PosePacket {
    PosePacket {
        t: 12.5,
        frame: 375,
        maxilla: Some(PacketBody {
            camera_from_body: Pose::from_axis_angle(Vector3::new(0.0, 0.5, 0.0), Vector3::new(-20.0, 10.0, 100.0)),
            tags_mask: 0b0000_0000_0111,
            tag_count: 3,
            rms_px: 0.25,
        }),
        mandible: Some(PacketBody {
            camera_from_body: Pose::from_axis_angle(Vector3::new(0.25, 0.5, 0.0), Vector3::new(-20.0, 50.0, 100.0)),
            tags_mask: 0b0011 << 12,
            tag_count: 2,
            rms_px: 0.5,
        }),
        maxilla_from_mandible: Some(Pose::from_axis_angle(Vector3::new(0.25, 0.0, 0.0), Vector3::new(0.0, 40.0, 0.0))),
        flags: 1 << 4,
    }
}

/// The vectors: (name, description, security, datagram).
fn vectors() -> Vec<(&'static str, &'static str, Security, Vec<u8>)> {
    let sealed = Security::Sealed(key());
    let lost = PosePacket { maxilla: None, mandible: None, maxilla_from_mandible: None, flags: 0b111, ..packet() };
    let ack = Ack { session: 0x0123_4567_89ab_cdef, highest_seq: 41, accepted: 40, lost: 2, rejected: 5 };
    vec![
        (
            "pose_sealed",
            "both bodies tracked, sealed under the key",
            sealed.clone(),
            encode_pose((0x0123_4567_89ab_cdef, 41, 1_795_000_000_000), &packet(), &sealed),
        ),
        (
            "pose_lost_sealed",
            "no body tracked (flags no_tags, maxilla:lost, mandible:lost), sealed",
            sealed.clone(),
            encode_pose((0x0123_4567_89ab_cdef, 42, 1_795_000_000_004), &lost, &sealed),
        ),
        (
            "pose_plaintext",
            "the same pose in development plaintext mode",
            Security::Plaintext,
            encode_pose((0x0123_4567_89ab_cdef, 41, 1_795_000_000_000), &packet(), &Security::Plaintext),
        ),
        (
            "ack_sealed",
            "the receiver (session 0xfedcba9876543210, its datagram 7) acknowledging",
            sealed.clone(),
            encode_ack((0xfedc_ba98_7654_3210, 7, 1_795_000_000_010), &ack, &sealed),
        ),
    ]
}

#[test]
fn the_golden_datagrams_are_what_this_build_encodes_and_decodes() {
    let made: Vec<Value> = vectors()
        .into_iter()
        .map(|(name, description, _, d)| json!({"name": name, "description": description, "hex": hex(&d)}))
        .collect();
    let doc = json!({
        "key_hex": key().to_hex(),
        "key_id": key().id(),
        "vectors": made,
    });
    if std::env::var_os("JAWTRACK_BLESS").is_some() {
        std::fs::write(FILE, serde_json::to_string_pretty(&doc).expect("json") + "\n").expect("writing the vectors");
    }
    let stored: Value = serde_json::from_str(&std::fs::read_to_string(FILE).expect("fixtures/wire/golden.json"))
        .expect("golden.json is JSON");
    assert_eq!(stored, doc, "the wire format changed: bless on purpose only (see this file's doc comment)");
    for (name, _, security, d) in vectors() {
        let back = decode(&d, &security).unwrap_or_else(|e| panic!("{name}: {e}"));
        match (name, back) {
            ("pose_sealed" | "pose_plaintext", Message::Pose(h, p)) => {
                assert_eq!((h.session, h.seq, p.frame, p.flags), (0x0123_4567_89ab_cdef, 41, 375, 1 << 4));
                let (a, t) = p
                    .maxilla_from_mandible
                    .expect("relative pose")
                    .distance_to(&packet().maxilla_from_mandible.expect("relative pose"));
                assert!(a < 1e-15 && t < 1e-12, "{name}");
            }
            ("pose_lost_sealed", Message::Pose(_, p)) => {
                assert!(p.maxilla.is_none() && p.maxilla_from_mandible.is_none() && p.flags == 0b111);
            }
            ("ack_sealed", Message::Ack(h, a)) => assert_eq!((h.seq, a.highest_seq, a.lost), (7, 41, 2)),
            (name, m) => panic!("{name} decoded as {m:?}"),
        }
    }
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}
