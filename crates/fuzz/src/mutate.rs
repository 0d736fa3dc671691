//! Mutators: they turn a valid input into a hostile one. Byte havoc (flips, interesting values,
//! block moves, splices; AFL's set) finds what a reader does with garbage; the structure-aware
//! mutators keep a JSON document or a text file parseable while they change one value, key or
//! line, so the input reaches the checks behind the syntax (ranges, counts, cross-references).

use rand::Rng;
use rand::seq::IndexedRandom;
use serde_json::Value;

/// How an input is structured, which picks the mutators that keep it readable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// One JSON document.
    Json,
    /// JSON lines.
    JsonLines,
    /// Whitespace-separated text lines (OBJ, ASCII PLY and STL).
    Text,
    /// Bytes without a syntax to keep.
    Binary,
}

/// Numbers that break arithmetic: zero, signs, the edges of the integer types, the smallest
/// and largest doubles, and values just past a float's integer precision.
const NUMBERS: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "2",
    "3",
    "255",
    "256",
    "65535",
    "65536",
    "4294967295",
    "4294967296",
    "9007199254740993",
    "18446744073709551615",
    "18446744073709551616",
    "-9223372036854775808",
    "1e308",
    "-1e308",
    "1.7976931348623157e308",
    "5e-324",
    "1e-300",
    "0.5",
    "-0.5",
    "1e999",
    "nan",
    "inf",
    "-inf",
    "NaN",
    "1e",
    "00",
    "0x10",
];

/// Mutates `input` in place: one to eight stacked mutations, structure-aware ones first
/// where the shape allows (half the time), `others` supplying material to splice from.
pub fn mutate(rng: &mut impl Rng, input: &mut Vec<u8>, shape: Shape, others: &[Vec<u8>], max_len: usize) {
    let structured = shape != Shape::Binary && rng.random_bool(0.5);
    let rounds = 1 << rng.random_range(0..4);
    for _ in 0..rounds {
        let done = structured
            && match shape {
                Shape::Json => json_document(rng, input),
                Shape::JsonLines => json_lines(rng, input),
                Shape::Text => text_lines(rng, input),
                Shape::Binary => false,
            };
        if !done {
            havoc(rng, input, others);
        }
    }
    input.truncate(max_len);
}

/// One AFL-style byte mutation.
pub fn havoc(rng: &mut impl Rng, data: &mut Vec<u8>, others: &[Vec<u8>]) {
    if data.is_empty() {
        data.extend((0..rng.random_range(1..16)).map(|_| rng.random::<u8>()));
        return;
    }
    let len = data.len();
    let at = rng.random_range(0..len);
    match rng.random_range(0..11) {
        0 => data[at] ^= 1 << rng.random_range(0..8),
        1 => data[at] = *[0u8, 1, 0x7f, 0x80, 0xff, b'-', b'.', b'e', b'"', b'\n', b' '].choose(rng).unwrap_or(&0),
        2 => data[at] = data[at].wrapping_add(rng.random_range(1..=35)),
        3 => data[at] = data[at].wrapping_sub(rng.random_range(1..=35)),
        4 => {
            // A 16- or 32-bit edge value, either byte order, where a binary count or size lives.
            let v: u32 = *[0, 1, 0x7f, 0x80, 0xff, 0x100, 0x7fff, 0x8000, 0xffff, 0x7fff_ffff, 0x8000_0000, u32::MAX]
                .choose(rng)
                .unwrap_or(&0);
            let bytes = if rng.random_bool(0.5) { v.to_le_bytes() } else { v.to_be_bytes() };
            let n = if rng.random_bool(0.5) { 2 } else { 4 };
            for (k, b) in bytes.iter().take(n).enumerate() {
                if let Some(slot) = data.get_mut(at + k) {
                    *slot = *b;
                }
            }
        }
        5 => {
            let end = (at + rng.random_range(1..=len.min(64))).min(len);
            data.drain(at..end);
        }
        6 => {
            let from = rng.random_range(0..len);
            let n = rng.random_range(1..=(len - from).min(64));
            let block: Vec<u8> = data[from..from + n].to_vec();
            data.splice(at..at, block);
        }
        7 => {
            let n = rng.random_range(1..=16);
            let fill = if rng.random_bool(0.5) { rng.random() } else { data[at] };
            data.splice(at..at, std::iter::repeat_n(fill, n));
        }
        8 => data.truncate(at),
        9 => {
            // Splice: this input's head with another's tail.
            if let Some(other) = others.choose(rng).filter(|o| !o.is_empty()) {
                let from = rng.random_range(0..other.len());
                data.truncate(at);
                data.extend_from_slice(&other[from..]);
            }
        }
        _ => {
            let n = rng.random_range(1..=len.min(8));
            for b in data.iter_mut().skip(at).take(n) {
                *b = rng.random();
            }
        }
    }
}

/// Changes one node of a JSON document; false when `data` is not one.
pub fn json_document(rng: &mut impl Rng, data: &mut Vec<u8>) -> bool {
    let Ok(mut value) = serde_json::from_slice::<Value>(data) else { return false };
    mutate_value(rng, &mut value);
    *data = if rng.random_bool(0.5) { value.to_string() } else { format!("{value:#}") }.into_bytes();
    true
}

/// Changes one line of a JSON lines file: its JSON, or the line itself (deleted, doubled,
/// moved, cut short); false when `data` is not text.
pub fn json_lines(rng: &mut impl Rng, data: &mut Vec<u8>) -> bool {
    with_lines(rng, data, |rng, lines, at| match rng.random_range(0..8) {
        how @ 0..3 => rearrange(rng, lines, at, how, 1),
        3 => {
            let cut = rng.random_range(0..=lines[at].len());
            lines[at] = lines[at].char_indices().take_while(|(i, _)| *i < cut).map(|(_, c)| c).collect();
        }
        _ => {
            let mut line = std::mem::take(&mut lines[at]).into_bytes();
            if !json_document(rng, &mut line) {
                havoc(rng, &mut line, &[]);
            }
            // A mutated line must stay one line for the reader to see it as one.
            lines[at] = String::from_utf8_lossy(&line).replace('\n', " ");
        }
    })
}

/// Changes one token or line of a whitespace-separated text file; false when `data` is not
/// text.
pub fn text_lines(rng: &mut impl Rng, data: &mut Vec<u8>) -> bool {
    with_lines(rng, data, |rng, lines, at| match rng.random_range(0..6) {
        how @ 0..3 => rearrange(rng, lines, at, how, 3),
        _ => {
            let mut tokens: Vec<String> = lines[at].split_whitespace().map(str::to_owned).collect();
            if tokens.is_empty() {
                return;
            }
            let k = rng.random_range(0..tokens.len());
            match rng.random_range(0..4) {
                0 => {
                    tokens.remove(k);
                }
                1 => tokens.insert(k, tokens[k].clone()),
                _ => tokens[k] = NUMBERS.choose(rng).unwrap_or(&"0").to_string(),
            }
            lines[at] = tokens.join(" ");
        }
    })
}

/// Splits text `data` into lines, lets `edit` change them around a random line, and joins
/// them back; false when `data` is not text or has no line.
fn with_lines<R: Rng>(rng: &mut R, data: &mut Vec<u8>, edit: impl FnOnce(&mut R, &mut Vec<String>, usize)) -> bool {
    let Ok(text) = std::str::from_utf8(data) else { return false };
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    if lines.is_empty() {
        return false;
    }
    let at = rng.random_range(0..lines.len());
    edit(rng, &mut lines, at);
    *data = (lines.join("\n") + "\n").into_bytes();
    true
}

/// Deletes line `at` (`how` 0), repeats it up to `most` times (1), or swaps it with another (2).
fn rearrange(rng: &mut impl Rng, lines: &mut Vec<String>, at: usize, how: u32, most: usize) {
    match how {
        0 => {
            lines.remove(at);
        }
        1 => {
            for _ in 0..rng.random_range(1..=most) {
                lines.insert(at, lines[at].clone());
            }
        }
        _ => {
            let to = rng.random_range(0..lines.len());
            lines.swap(at, to);
        }
    }
}

/// Mutates one node, chosen uniformly among the document's nodes.
fn mutate_value(rng: &mut impl Rng, root: &mut Value) {
    let count = count_nodes(root);
    let pick = rng.random_range(0..count);
    let donor = pick_node(root, rng.random_range(0..count)).cloned();
    let mut seen = 0;
    let mut donor = donor;
    visit_nth(root, pick, &mut seen, &mut |node| change(rng, node, donor.take()));
}

fn count_nodes(v: &Value) -> usize {
    1 + match v {
        Value::Array(a) => a.iter().map(count_nodes).sum(),
        Value::Object(o) => o.values().map(count_nodes).sum(),
        _ => 0,
    }
}

fn pick_node(v: &Value, n: usize) -> Option<&Value> {
    if n == 0 {
        return Some(v);
    }
    let mut n = n - 1;
    let children: Box<dyn Iterator<Item = &Value>> = match v {
        Value::Array(a) => Box::new(a.iter()),
        Value::Object(o) => Box::new(o.values()),
        _ => return None,
    };
    for child in children {
        let size = count_nodes(child);
        if n < size {
            return pick_node(child, n);
        }
        n -= size;
    }
    None
}

fn visit_nth(v: &mut Value, n: usize, seen: &mut usize, f: &mut dyn FnMut(&mut Value)) -> bool {
    if *seen == n {
        f(v);
        return true;
    }
    *seen += 1;
    match v {
        Value::Array(a) => a.iter_mut().any(|c| visit_nth(c, n, seen, f)),
        Value::Object(o) => o.values_mut().any(|c| visit_nth(c, n, seen, f)),
        _ => false,
    }
}

/// One change to a node: a hostile value in its place, a neighbour lost or doubled, a key
/// removed, or another node of the document (`donor`) grafted in.
fn change(rng: &mut impl Rng, node: &mut Value, donor: Option<Value>) {
    match rng.random_range(0..10) {
        0 => {
            if let Some(d) = donor {
                *node = d;
            }
        }
        1 => match node {
            Value::Array(a) if !a.is_empty() => {
                let k = rng.random_range(0..a.len());
                a.remove(k);
            }
            Value::Object(o) if !o.is_empty() => {
                let k = rng.random_range(0..o.len());
                let key = o.keys().nth(k).cloned().unwrap_or_default();
                o.remove(&key);
            }
            _ => *node = Value::Null,
        },
        2 => match node {
            Value::Array(a) if !a.is_empty() => {
                let k = rng.random_range(0..a.len());
                for _ in 0..rng.random_range(1..40) {
                    a.insert(k, a[k].clone());
                }
            }
            Value::Object(o) => {
                o.insert("unexpected".into(), Value::from(1));
            }
            _ => *node = Value::Array(vec![node.clone()]),
        },
        3 => {
            *node = [
                Value::Null,
                Value::Bool(true),
                Value::from(""),
                Value::Array(vec![]),
                Value::Object(Default::default()),
            ]
            .choose(rng)
            .cloned()
            .unwrap_or(Value::Null)
        }
        4 => *node = Value::from("x".repeat(rng.random_range(0..300))),
        _ => {
            // A hostile number (kept as JSON: `nan`, `inf` and `1e999` cannot be).
            let text = NUMBERS.choose(rng).unwrap_or(&"0");
            *node = serde_json::from_str(text).unwrap_or_else(|_| match node.as_f64() {
                Some(x) => Value::from(x * [-1.0, 1e10, 1e-10, 0.5, 1.0 + 1e-9].choose(rng).unwrap_or(&-1.0)),
                None => Value::from(-1),
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn a_json_mutation_keeps_json_and_changes_it() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let seed = br#"{"version":3,"bodies":[{"name":"maxilla","tags":[{"id":0,"size":10.6}]}]}"#.to_vec();
        let (mut changed, tries) = (0, 200);
        for _ in 0..tries {
            let mut data = seed.clone();
            assert!(json_document(&mut rng, &mut data));
            let value: Value = serde_json::from_slice(&data).expect("still JSON");
            changed += usize::from(value != serde_json::from_slice::<Value>(&seed).expect("the seed is JSON"));
        }
        // A few changes are no-ops (a key removed from an empty object, a donor equal to its node).
        assert!(changed > tries * 3 / 4, "{changed} of {tries} mutations changed the document");
    }

    #[test]
    fn json_lines_mutations_keep_lines_and_reach_every_line() {
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let seed = b"{\"a\":1}\n{\"b\":2}\n{\"c\":3}\n".to_vec();
        let mut touched = [false; 3];
        for _ in 0..300 {
            let mut data = seed.clone();
            assert!(json_lines(&mut rng, &mut data));
            let text = String::from_utf8(data).expect("still text");
            for (k, key) in ["\"a\":1", "\"b\":2", "\"c\":3"].iter().enumerate() {
                touched[k] |= !text.contains(key);
            }
        }
        assert_eq!(touched, [true; 3], "every line was changed at least once");
    }

    #[test]
    fn text_mutations_put_hostile_numbers_in_tokens() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let seed = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec();
        let hostile = (0..300)
            .filter(|_| {
                let mut data = seed.clone();
                assert!(text_lines(&mut rng, &mut data));
                let text = String::from_utf8(data).expect("still text");
                ["nan", "inf", "4294967295", "1e999", "1e308", "5e-324", "65536", "-1", "0x10"]
                    .iter()
                    .any(|n| text.contains(n))
            })
            .count();
        // A quarter of the mutations put one of 31 numbers in a token; 9 of them are listed.
        assert!(hostile > 10, "{hostile} of 300 mutants carried a hostile number");
    }

    #[test]
    fn havoc_changes_bytes_and_respects_the_length_cap() {
        let mut rng = ChaCha8Rng::seed_from_u64(10);
        let seed: Vec<u8> = (0..=255).collect();
        let others = vec![vec![9u8; 1000]];
        let mut differing = 0;
        for _ in 0..500 {
            let mut data = seed.clone();
            mutate(&mut rng, &mut data, Shape::Binary, &others, 300);
            assert!(data.len() <= 300);
            differing += usize::from(data != seed);
        }
        assert!(differing > 480, "{differing} of 500 mutants differ from the seed");
    }
}
