//! Reading files that are complete, cut short, killed mid-chunk, interrupted, or not MCAP.

use crate::cone::{self, Surface};
use crate::fixture::write_file;
use crate::repose::repose_file;
use crate::shear::{SAMPLES, force, shear_fixture};
use tilth_tools::reduce::plot::shear_svg;
use tilth_tools::reduce::*;

fn scalars_only() -> ReadOptions {
    ReadOptions {
        cloud: CloudChoice::None,
    }
}

/// The made-up curve's peak (140 N at 3 mm) lies in the third of four chunks of 126 samples.
const PEAK: f64 = 140.0;
const PEAK_AT: f64 = 3e-3;
const PER_CHUNK: usize = 126;

/// The largest force among the first `n` samples.
fn peak_of_first(n: usize) -> f64 {
    (0..n)
        .map(|k| force(k as f64 * 1e-5, PEAK, PEAK_AT))
        .fold(f64::NEG_INFINITY, f64::max)
}

/// A finished file cut in the middle of its third chunk (a disk that filled up, a copy that
/// stopped short): the reader stops at the break and says the file is incomplete, and the
/// reducer works on the two whole chunks before it, whose peak is lower than the run's.
#[test]
fn cut_file_reads_its_whole_chunks_and_says_incomplete() {
    let (f, ends) = shear_fixture(50e3, PEAK, PEAK_AT, PER_CHUNK, SAMPLES);
    let bytes = f.finish();
    let whole = write_file("shear-whole.mcap", &bytes);
    let run = read_run(&whole, &scalars_only()).unwrap();
    assert!(run.completeness.complete, "{:?}", run.completeness);
    assert_eq!(
        shear(&run, &ShearOptions::default())
            .unwrap()
            .analysis
            .peak_shear_force_n,
        PEAK
    );

    // Cut inside the third chunk's compressed data: the chunk record starts where the
    // second chunk's message indexes end (opcode 0x06, then its length).
    assert_eq!(
        bytes[ends[1]], 0x06,
        "a chunk starts at the end of the second"
    );
    let length = u64::from_le_bytes(bytes[ends[1] + 1..ends[1] + 9].try_into().unwrap());
    let cut = ends[1] + 9 + length as usize / 2;
    let path = write_file("shear-cut.mcap", &bytes[..cut]);
    let run = read_run(&path, &scalars_only()).unwrap();
    assert!(!run.completeness.complete);
    let reason = run.completeness.reason.clone().unwrap();
    assert!(reason.contains("breaks off"), "{reason}");

    let r = shear(&run, &ShearOptions::default()).unwrap();
    assert!(!r.source.complete);
    assert_eq!(r.analysis.curve.len(), 2 * PER_CHUNK, "whole chunks only");
    assert_eq!(r.analysis.peak_shear_force_n, peak_of_first(2 * PER_CHUNK));
    assert!(r.analysis.peak_shear_force_n < PEAK);
    let json = serde_json::to_value(&r).unwrap();
    assert_eq!(json["complete"], false);
    assert!(
        json["incomplete_reason"]
            .as_str()
            .unwrap()
            .contains("breaks off")
    );
    let svg = shear_svg(&r).unwrap();
    assert!(svg.contains("INCOMPLETE"));
    std::fs::write(path.with_extension("svg"), svg).unwrap();
}

/// Every cut point inside the data reads without error and never passes for complete.
#[test]
fn any_cut_is_incomplete_never_an_error_after_the_header() {
    let (f, ends) = shear_fixture(50e3, PEAK, PEAK_AT, PER_CHUNK, SAMPLES);
    let bytes = f.finish();
    let first = ends[0] / 2;
    for cut in (first..bytes.len()).step_by(997) {
        let path = write_file("shear-cut-sweep.mcap", &bytes[..cut]);
        let run = read_run(&path, &scalars_only()).unwrap();
        assert!(
            !run.completeness.complete,
            "cut at {cut} of {}",
            bytes.len()
        );
        let n = run.scalars.get("shear_force").map_or(0, |s| s.len());
        assert!(
            n % PER_CHUNK == 0 || n == SAMPLES,
            "cut at {cut}: {n} samples, whole chunks only"
        );
    }
}

/// A run killed with SIGKILL while a chunk is open: the file ends in a chunk whose header
/// still holds the writer's placeholders (length u64::MAX). The reader skips it without
/// trying to allocate it, and the numbers are those of the closed chunks.
#[test]
fn killed_run_reads_up_to_its_last_closed_chunk() {
    let (f, ends) = shear_fixture(50e3, PEAK, PEAK_AT, PER_CHUNK, 300);
    let bytes = f.killed_now();
    assert!(
        bytes.len() > *ends.last().unwrap(),
        "the open chunk is on disk"
    );
    let path = write_file("shear-killed.mcap.partial", &bytes);
    let run = read_run(&path, &scalars_only()).unwrap();
    assert!(!run.completeness.complete);
    let r = shear(&run, &ShearOptions::default()).unwrap();
    assert_eq!(r.analysis.curve.len(), 2 * PER_CHUNK);
    assert_eq!(r.analysis.peak_shear_force_n, peak_of_first(2 * PER_CHUNK));
    assert_eq!(
        run.last_time_s,
        Some(0.5 + (2 * PER_CHUNK - 1) as f64 * 2e-3)
    );
}

/// SIGINT/SIGTERM: the run closes its file properly but keeps the `.partial` name; the file
/// reads whole and is still not complete.
#[test]
fn interrupted_run_keeps_partial_name_and_is_incomplete() {
    let (f, _) = shear_fixture(50e3, PEAK, PEAK_AT, PER_CHUNK, 200);
    let path = write_file("shear-interrupted.mcap.partial", &f.finish());
    let run = read_run(&path, &scalars_only()).unwrap();
    assert!(!run.completeness.complete);
    assert!(run.completeness.reason.unwrap().contains(".partial"));
    assert_eq!(run.scalars["shear_force"].len(), 200);
}

#[test]
fn not_an_mcap_file_is_an_error() {
    for (name, bytes) in [
        ("empty.mcap", &b""[..]),
        ("text.mcap", &b"time,force\n0,1\n"[..]),
    ] {
        let path = write_file(name, bytes);
        let e = read_run(&path, &scalars_only()).unwrap_err();
        assert!(matches!(e, ReduceError::NotMcap { .. }), "{name}: {e}");
        assert!(e.to_string().contains(name), "{e}");
    }
    let e = read_run("/nonexistent/run.mcap", &scalars_only()).unwrap_err();
    assert!(matches!(e, ReduceError::Io { .. }), "{e}");
}

/// Metadata records come back as written; frames can be chosen by index or time.
#[test]
fn metadata_and_frame_choice() {
    let (heap, _) = cone::synthetic_cone(35.0, 2, Surface::Rings);
    let path = repose_file("frames.mcap", &heap);
    let run = read_run(&path, &ReadOptions::default()).unwrap();
    assert_eq!(run.metadata["tilth.run"]["seed"], "42");
    assert_eq!(run.metadata["tilth.run"]["factor.rolling_friction"], "0.19");
    assert_eq!(
        run.metadata_value(EXPERIMENT_RECORD, "type").unwrap(),
        "repose"
    );
    assert_eq!(run.cloud_frames, 2);
    assert_eq!(run.scalars["kinetic_energy"].value, vec![1e-3, 1e-9]);
    let last = run.cloud().unwrap();
    assert_eq!(last.time_s, 120.0);
    assert_eq!(last.len(), heap.len());
    // f32 in the file: positions come back to within float precision.
    assert!((last.z[7] - heap.z[7]).abs() < 1e-8);
    assert_eq!(last.id[7], 7);

    for choice in [CloudChoice::Index(0), CloudChoice::AtOrBefore(60.0)] {
        let run = read_run(&path, &ReadOptions { cloud: choice }).unwrap();
        let c = run.cloud().unwrap();
        assert_eq!(c.time_s, 1.0, "{choice:?}");
        assert!((c.z[7] - heap.z[7] - 0.005).abs() < 1e-8);
    }
    let run = read_run(
        &path,
        &ReadOptions {
            cloud: CloudChoice::AtOrBefore(0.5),
        },
    )
    .unwrap();
    assert!(run.cloud.is_none());
    let e = repose(&run, &ReposeOptions::default()).unwrap_err();
    assert!(e.to_string().contains("/particles"), "{e}");

    let missing = run.metadata_number("tilth.experiment", "nope").unwrap_err();
    assert!(missing.to_string().contains("\"nope\""), "{missing}");
}
