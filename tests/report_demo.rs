//! `hammerstein demo` end to end: exit 0, the report exists, and the final validation MSE it prints
//! is below the linear model's.

use std::process::Command;

fn number_after(line: &str, key: &str) -> Option<f64> {
    let rest = &line[line.find(key)? + key.len()..];
    rest.split_whitespace()
        .next()?
        .trim_end_matches(')')
        .parse()
        .ok()
}

#[test]
fn demo_finds_the_effects_and_writes_the_report() {
    let dir = std::env::temp_dir().join(format!("hammerstein-demo-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = Command::new(env!("CARGO_BIN_EXE_hammerstein"))
        .args(["demo", "--seed", "3", "--out"])
        .arg(&dir)
        .output()
        .expect("run the demo");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "demo failed: {}\n{stdout}",
        String::from_utf8_lossy(&out.stderr)
    );
    let index = dir.join("index.html");
    assert!(index.exists(), "no report at {}", index.display());
    let html = std::fs::read_to_string(&index).unwrap();
    assert!(html.contains("id=\"residual-direction\"") && html.contains("id=\"steps\""));
    assert!(dir.join("step-0").join("index.html").exists());
    // "validation MSE: linear X → final Y (noise floor Z)"
    let line = stdout
        .lines()
        .find(|l| l.starts_with("validation MSE: linear"))
        .unwrap_or_else(|| panic!("no summary line in\n{stdout}"));
    let linear = number_after(line, "linear").unwrap();
    let fin = number_after(line, "final").unwrap();
    let floor = number_after(line, "noise floor").unwrap();
    assert!(
        fin < linear,
        "final {fin} not below linear {linear}\n{stdout}"
    );
    // the hidden effects are found: the error reaches the noise floor within 30 %
    assert!(
        fin < 1.3 * floor,
        "final {fin} far above the noise floor {floor}\n{stdout}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn demo_rejects_a_too_short_record() {
    let out = Command::new(env!("CARGO_BIN_EXE_hammerstein"))
        .args([
            "demo",
            "--samples",
            "50",
            "--out",
            "/nonexistent/never-written",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("too short"));
}
