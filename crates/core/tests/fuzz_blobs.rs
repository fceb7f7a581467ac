//! Blob fuzzing on stable, in every `cargo test`: the decoder, the validator with its plausibility
//! bound, and the compensator, on structured and raw blobs (generators and properties in
//! `fuzz_support`). `TCOMP_FUZZ_CASES` sets the number of cases per property (default 100,000); the
//! long run is the `fuzz_blobs` example.
#![allow(clippy::unwrap_used, missing_docs)]

mod fuzz_support;

use fuzz_support::*;
use proptest::prelude::*;
use proptest::strategy::ValueTree;
use proptest::test_runner::{Config, TestRunner};

fn cases() -> u32 {
    std::env::var("TCOMP_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(100_000)
}

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: cases(),
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn structured_blobs_decode_safely_and_accepted_ones_stay_bounded(
        (n, seed, edits) in structured_case(),
        samples in samples(),
        points in fractions(),
    ) {
        if let Some(blob) = structured_blob(n, seed, &edits) {
            check_blob(&blob, &samples, &points).map_err(TestCaseError::fail)?;
        }
    }

    #[test]
    fn raw_and_bit_flipped_blobs_decode_safely_and_accepted_ones_stay_bounded(
        body in proptest::collection::vec(any::<u8>(), 0..700),
        (n, seed) in (1usize..=40, 1u32..u32::MAX),
        flips in proptest::collection::vec((any::<usize>(), 1u8..=255), 1..6),
        reseal in any::<bool>(),
        samples in samples(),
        points in fractions(),
    ) {
        let _ = tcomp_core::HostModel::decode(&body);
        check_blob(&raw_blob(&body), &samples, &points).map_err(TestCaseError::fail)?;
        let flipped = flipped_blob(n, seed, &flips, reseal);
        let accepted = check_blob(&flipped, &samples, &points).map_err(TestCaseError::fail)?;
        // Without a new CRC every flip is caught by the checksum.
        prop_assert!(reseal || !accepted, "a corrupted blob was accepted");
    }
}

/// The fuzzing is not vacuous: structured cases reach acceptance, and rejection for each of the
/// value-level reasons (so the properties above are exercised on accepted models).
#[test]
fn structured_cases_reach_every_verdict() {
    let mut runner = TestRunner::new(Config::default());
    let (strategy, samples, points) = (structured_case(), samples(), fractions());
    let mut tally = Tally::default();
    for _ in 0..3000 {
        let (n, seed, edits) = strategy.new_tree(&mut runner).unwrap().current();
        let s = samples.new_tree(&mut runner).unwrap().current();
        let p = points.new_tree(&mut runner).unwrap().current();
        let Some(blob) = structured_blob(n, seed, &edits) else {
            continue;
        };
        tally.cases += 1;
        match HostModel::decode(&blob) {
            Ok(_) => tally.accepted += 1,
            Err(e) => tally.rejected[reason_index(&e)] += 1,
        }
        check_blob(&blob, &s, &p).unwrap();
    }
    assert!(tally.accepted > tally.cases / 10, "{tally:?}");
    for reason in ["non-finite", "inconsistent", "implausible", "unknown tag"] {
        let i = REASONS.iter().position(|r| *r == reason).unwrap();
        assert!(tally.rejected[i] > 0, "no {reason} rejection: {tally:?}");
    }
}
