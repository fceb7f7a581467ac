//! The demo's report (`tcomp demo`, rendered by `render/html`) renders in a real headless browser
//! (Debian's `chromium`): the page loads, every SVG plot lays out and holds data (the report's
//! inline check writes the counts on `<body>`), and the verdict is there. So does `tcomp report` on
//! the bursty LSM6DSM record (25 bursts of 5 s every 5 min), whose plots were once empty. The
//! browser part is skipped, with a message, when chromium is not installed.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::process::Command;

/// The DOM of `html` after chromium ran its scripts; `None` (with a message) without chromium.
fn dump_dom(html: &std::path::Path) -> Option<String> {
    let Some(bin) = chromium() else {
        println!("SKIPPED: chromium is not installed (apt-get install -y chromium)");
        return None;
    };
    let profile = tempfile::tempdir().unwrap();
    let out = Command::new(bin)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-background-networking",
            "--disable-component-update",
            "--no-first-run",
            "--enable-logging=stderr",
            "--v=0",
        ])
        .arg(format!("--user-data-dir={}", profile.path().display()))
        .arg("--dump-dom")
        .arg(format!("file://{}", html.display()))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "chromium failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("Uncaught"), "script error: {err}");
    Some(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// Every one of the page's `plots` plots laid out with data, as its inline check counted.
fn assert_laid_out(dom: &str, plots: usize) {
    assert!(
        dom.contains(&format!("data-plots=\"{plots}\""))
            && dom.contains(&format!("data-plots-ok=\"{plots}\"")),
        "not every plot laid out; body: {}",
        dom.lines().find(|l| l.contains("<body")).unwrap_or("")
    );
}

/// The data marks of each plot of a report (its `data-points` attributes).
fn points_per_plot(html: &str) -> Vec<usize> {
    html.split("<svg class=\"plot\"")
        .skip(1)
        .map(|p| {
            p.split("data-points=\"")
                .nth(1)
                .and_then(|v| v.split('"').next())
                .and_then(|v| v.parse().ok())
                .unwrap_or(0)
        })
        .collect()
}

fn chromium() -> Option<String> {
    ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .find(|b| {
            Command::new(b)
                .arg("--version")
                .output()
                .is_ok_and(|o| o.status.success())
        })
        .map(|s| s.to_string())
}

#[test]
fn demo_report_renders_in_headless_chromium() {
    let dir = tempfile::tempdir().unwrap();
    let demo = Command::new(env!("CARGO_BIN_EXE_tcomp"))
        .args(["demo", "--seed", "3", "--step", "5", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(
        demo.status.success(),
        "tcomp demo failed: {}",
        String::from_utf8_lossy(&demo.stderr)
    );
    let html = dir.path().join("report.html");
    let text = std::fs::read_to_string(&html).unwrap();
    assert!(text.matches("<svg").count() >= 4, "too few plots");
    assert!(
        !text.contains("http://")
            || text.matches("http://").count()
                == text.matches("xmlns=\"http://www.w3.org/2000/svg\"").count(),
        "no network references"
    );
    let Some(dom) = dump_dom(&html) else {
        return;
    };
    let plots = text.matches("<svg class=\"plot\"").count();
    assert_laid_out(&dom, plots);
    assert!(dom.contains("id=\"verdict\""), "verdict missing");
    let verdict = dom
        .split("data-verdict=\"")
        .nth(1)
        .and_then(|v| v.split('"').next())
        .unwrap_or("?");
    println!("chromium rendered {plots} plots; demo verdict {verdict}");
}

/// The bursty LSM6DSM record: a model fitted before 4000 s, reported on the rest (the held-out
/// window): every plot holds data, units come from the column names, the channel is in the
/// title, and the page lays out in chromium.
#[test]
fn bursty_record_report_has_non_empty_plots() {
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../data/realdata/lsm6dsm_tvac_cold_ramp.csv");
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("gyro_x.tcm");
    let html = dir.path().join("report.html");
    let run = |args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_tcomp"))
            .args(args)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    let d = data.to_str().unwrap();
    run(&[
        "fit",
        "--data",
        d,
        "--target",
        "gyro_x_rad_s",
        "--reference-value",
        "0",
        "--feature",
        "temp_lsm6dsm_C",
        "--until",
        "4000",
        "--average",
        "2",
        "--quiet",
        "--out",
        model.to_str().unwrap(),
    ]);
    run(&[
        "report",
        "--model",
        model.to_str().unwrap(),
        "--data",
        d,
        "--from",
        "4000",
        "--quiet",
        "--out",
        html.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(&html).unwrap();
    let points = points_per_plot(&text);
    assert!(points.len() >= 3, "too few plots: {points:?}");
    assert!(points.iter().all(|&n| n > 0), "an empty plot: {points:?}");
    assert!(
        text.contains("<h1>tcomp report: gyro_x_rad_s (rad/s)"),
        "title"
    );
    assert!(
        text.contains("residual (rad/s)") && text.contains("temperature (°C)"),
        "units"
    );
    assert!(!text.contains(" ()"), "an axis without its unit");
    let Some(dom) = dump_dom(&html) else {
        return;
    };
    assert_laid_out(&dom, points.len());
    println!(
        "chromium rendered {} plots of the LSM6DSM record: {points:?}",
        points.len()
    );
}

/// `tcomp calibrate` on the real MEMS cycle: one page, a section per channel, and in each section
/// at least one plot that holds data; the page lays out in chromium with every plot non-empty.
#[test]
fn calibrate_report_has_a_non_empty_plot_per_channel() {
    let spec = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../data/realdata/mems_thermal_cycle.calibrate.toml");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cal");
    let o = Command::new(env!("CARGO_BIN_EXE_tcomp"))
        .args(["calibrate", "--quiet", "--no-diagnosis", "--out"])
        .arg(&out)
        .arg(&spec)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let html = out.join("report.html");
    let text = std::fs::read_to_string(&html).unwrap();
    let sections: Vec<&str> = text.split("<h2 id=\"").skip(1).collect();
    assert_eq!(sections.len(), 6, "one section per channel");
    for s in &sections {
        let name = s.split('"').next().unwrap_or("?");
        let points = points_per_plot(s);
        assert!(
            points.iter().any(|&n| n > 0),
            "channel {name}: no plot with data ({points:?})"
        );
    }
    let all = points_per_plot(&text);
    assert!(all.iter().all(|&n| n > 0), "an empty plot: {all:?}");
    let Some(dom) = dump_dom(&html) else {
        return;
    };
    assert_laid_out(&dom, all.len());
    println!(
        "chromium rendered {} plots of the calibration page",
        all.len()
    );
}
