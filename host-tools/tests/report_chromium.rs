//! The demo's report (`tcomp demo`, rendered by `render/html`) renders in a real headless browser
//! (Debian's `chromium`): the page loads, every SVG plot lays out (the report's inline check writes
//! the counts on `<body>`), and the verdict is there. Skipped, with a message, when chromium is not
//! installed.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::process::Command;

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
    let Some(bin) = chromium() else {
        println!("SKIPPED: chromium is not installed (apt-get install -y chromium)");
        return;
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
    let dom = String::from_utf8_lossy(&out.stdout);
    let err = String::from_utf8_lossy(&out.stderr);
    let plots = text.matches("<svg class=\"plot\"").count();
    assert!(
        dom.contains(&format!("data-plots=\"{plots}\""))
            && dom.contains(&format!("data-plots-ok=\"{plots}\"")),
        "not every plot laid out; body: {}",
        dom.lines().find(|l| l.contains("<body")).unwrap_or("")
    );
    assert!(!err.contains("Uncaught"), "script error: {err}");
    assert!(dom.contains("id=\"verdict\""), "verdict missing");
    let verdict = dom
        .split("data-verdict=\"")
        .nth(1)
        .and_then(|v| v.split('"').next())
        .unwrap_or("?");
    println!("chromium rendered {plots} plots; demo verdict {verdict}");
}
