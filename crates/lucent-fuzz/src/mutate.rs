//! Byte-level and text-aware mutations (the classic set of AFL and libFuzzer: bit flips,
//! interesting integers, block deletion, insertion and duplication, splicing, plus number
//! tokens swapped for hostile ones, which is what breaks text formats).

use rand::Rng;
use rand_pcg::Pcg64Mcg;

/// Inputs never grow past this many bytes: loaders' cost scales with size, and the bugs that
/// matter show on small files.
pub const MAX_LEN: usize = 16 * 1024;

const INTERESTING_U32: [u32; 12] =
    [0, 1, 2, 3, 0x7f, 0x80, 0xff, 0xffff, 0x7fff_ffff, 0x8000_0000, 0xffff_ffff, 0x0100_0000];

const HOSTILE_NUMBERS: [&str; 16] = [
    "0",
    "-1",
    "1",
    "-0",
    "nan",
    "inf",
    "-inf",
    "1e308",
    "1e-320",
    "4294967295",
    "4294967296",
    "2147483648",
    "99999999999999999999",
    "1e38",
    "-2147483649",
    "65536",
];

/// Applies one to four random mutations to `data`, drawing splice material from `other`.
pub fn mutate(data: &mut Vec<u8>, other: &[u8], rng: &mut Pcg64Mcg) {
    for _ in 0..rng.random_range(1..=4) {
        mutate_once(data, other, rng);
    }
    data.truncate(MAX_LEN);
}

fn mutate_once(data: &mut Vec<u8>, other: &[u8], rng: &mut Pcg64Mcg) {
    if data.is_empty() {
        data.push(rng.random());
        return;
    }
    let n = data.len();
    let at = rng.random_range(0..n);
    match rng.random_range(0..10) {
        0 => data[at] ^= 1 << rng.random_range(0..8),
        1 => data[at] = rng.random(),
        2 => {
            // An interesting integer, 1, 2 or 4 bytes, either endianness.
            let v = INTERESTING_U32[rng.random_range(0..INTERESTING_U32.len())];
            let width = [1, 2, 4][rng.random_range(0..3)];
            let bytes = if rng.random() { v.to_le_bytes() } else { v.to_be_bytes() };
            for (k, &b) in bytes[4 - width..].iter().enumerate() {
                if let Some(d) = data.get_mut(at + k) {
                    *d = b;
                }
            }
        }
        3 => {
            let len = rng.random_range(1..=(n - at).min(64));
            data.drain(at..at + len);
        }
        4 => {
            let len = rng.random_range(1..=16);
            let bytes: Vec<u8> = (0..len).map(|_| rng.random()).collect();
            data.splice(at..at, bytes);
        }
        5 => {
            // Duplicate a block somewhere else (repeats elements and lines).
            let len = rng.random_range(1..=(n - at).min(128));
            let block = data[at..at + len].to_vec();
            let to = rng.random_range(0..=n);
            data.splice(to..to, block);
        }
        6 if !other.is_empty() => {
            // Splice: our head, the other input's tail.
            let from = rng.random_range(0..other.len());
            data.truncate(at);
            data.extend_from_slice(&other[from..]);
        }
        7 | 8 => replace_number(data, at, rng),
        _ => data.truncate(at.max(1)),
    }
}

/// Replaces the number token at or after `at` with a hostile one.
fn replace_number(data: &mut Vec<u8>, at: usize, rng: &mut Pcg64Mcg) {
    let is_num = |b: u8| b.is_ascii_digit() || matches!(b, b'.' | b'-' | b'+' | b'e' | b'E');
    let Some(start) = (at..data.len()).find(|&k| data[k].is_ascii_digit()) else { return };
    let start = (0..start).rev().take_while(|&k| is_num(data[k])).last().unwrap_or(start);
    let end = (start..data.len()).find(|&k| !is_num(data[k])).unwrap_or(data.len());
    let token = HOSTILE_NUMBERS[rng.random_range(0..HOSTILE_NUMBERS.len())];
    data.splice(start..end, token.bytes());
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn mutations_change_inputs_and_respect_the_size_cap() {
        let mut rng = Pcg64Mcg::seed_from_u64(7);
        let seed = b"v 1.0 2.0 3.0\nf 1 2 3\n".to_vec();
        let mut changed = 0;
        for _ in 0..1000 {
            let mut d = seed.clone();
            mutate(&mut d, &seed, &mut rng);
            changed += usize::from(d != seed);
            assert!(d.len() <= MAX_LEN);
        }
        assert!(changed > 900, "{changed}");
        let mut d = b"x 12.5 y".to_vec();
        replace_number(&mut d, 0, &mut rng);
        assert!(
            d.starts_with(b"x ") && d.ends_with(b" y") && d != b"x 12.5 y",
            "{}",
            String::from_utf8_lossy(&d)
        );
    }
}
