//! The long fuzzing run: `cargo run --release -p tcomp-core --example fuzz_blobs -- 10000000`.
//!
//! Draws the same structured and raw blob cases as the `fuzz_blobs` test (half each, from
//! `tests/fuzz_support`), decodes each into the host's and the firmware's model types, runs every
//! accepted model through `Rbf::eval_split` over its range box and `Channel::step` on good, extreme,
//! NaN and infinite inputs, and counts: cases, panics (caught, so the run goes on and reports them),
//! accepted models, accepted models that broke a property (left the plausibility bound, gave a
//! non-finite output without a fault, or raised a model fault on an ordinary raw value), and
//! rejections by reason. Exits non-zero if any panic or property violation occurred. An optional
//! second argument seeds the generator (default 1).
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

#[path = "../tests/fuzz_support/mod.rs"]
mod fuzz_support;

use fuzz_support::*;
use proptest::prelude::*;
use proptest::strategy::ValueTree;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::time::Instant;

fn main() {
    let mut args = std::env::args().skip(1);
    let cases: u64 = args
        .next()
        .and_then(|a| a.parse().ok())
        .unwrap_or(1_000_000);
    let seed: u64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(1);
    let mut seed_bytes = [0u8; 32];
    seed_bytes[..8].copy_from_slice(&seed.to_le_bytes());
    let rng = TestRng::from_seed(RngAlgorithm::ChaCha, &seed_bytes);
    let mut runner = TestRunner::new_with_rng(Config::default(), rng);

    let structured = structured_case();
    let raw = (
        proptest::collection::vec(any::<u8>(), 0..700),
        (1usize..=40, 1u32..u32::MAX),
        proptest::collection::vec((any::<usize>(), 1u8..=255), 1..6),
        any::<bool>(),
    );
    let (samples, points) = (samples(), fractions());
    // Silence the default hook: panics are counted, the first one is printed below.
    std::panic::set_hook(Box::new(|_| {}));

    let start = Instant::now();
    let mut tally = Tally::default();
    let mut panics = 0u64;
    let mut first_failure: Option<String> = None;
    for i in 0..cases {
        let s = samples.new_tree(&mut runner).unwrap().current();
        let p = points.new_tree(&mut runner).unwrap().current();
        let blobs: Vec<Vec<u8>> = if i % 2 == 0 {
            let (n, seed, edits) = structured.new_tree(&mut runner).unwrap().current();
            structured_blob(n, seed, &edits).into_iter().collect()
        } else {
            let (body, (n, seed), flips, reseal) = raw.new_tree(&mut runner).unwrap().current();
            vec![raw_blob(&body), flipped_blob(n, seed, &flips, reseal)]
        };
        for blob in &blobs {
            tally.cases += 1;
            let verdict = catch_unwind(AssertUnwindSafe(|| {
                let reason = HostModel::decode(blob).err().map(|e| reason_index(&e));
                (reason, check_blob(blob, &s, &p))
            }));
            match verdict {
                Err(_) => {
                    panics += 1;
                    first_failure.get_or_insert_with(|| format!("panic on blob {blob:02x?}"));
                }
                Ok((reason, result)) => {
                    match reason {
                        None => tally.accepted += 1,
                        Some(r) => tally.rejected[r] += 1,
                    }
                    if let Err(e) = result {
                        tally.implausible += 1;
                        first_failure.get_or_insert(e);
                    }
                }
            }
        }
        if (i + 1) % 1_000_000 == 0 {
            eprintln!("{} cases, {:.0} s", i + 1, start.elapsed().as_secs_f64());
        }
    }
    let secs = start.elapsed().as_secs_f64();
    println!(
        "fuzz_blobs: {} cases drawn ({} blobs decoded), seed {seed}, {secs:.1} s ({:.1} µs per blob)",
        cases,
        tally.cases,
        1e6 * secs / tally.cases.max(1) as f64
    );
    println!("  panics: {panics}");
    println!(
        "  accepted: {} (host types); accepted but implausible or misbehaving: {}",
        tally.accepted, tally.implausible
    );
    println!("  rejected (host types), by reason:");
    for (name, n) in REASONS.iter().zip(tally.rejected) {
        if n > 0 {
            println!("    {name:<20} {n}");
        }
    }
    if let Some(f) = first_failure {
        println!("  first failure: {f}");
    }
    if panics > 0 || tally.implausible > 0 {
        std::process::exit(1);
    }
}
