//! `docs/cli.md` is the command line's own help: `hammerstein --help` and `hammerstein COMMAND
//! --help` for every command that `hammerstein --help` lists. The test fails when the page and
//! the binary differ; `HAMMERSTEIN_BLESS=1 cargo test --test cli_docs` rewrites the page from
//! the binary.

use std::path::PathBuf;
use std::process::Command;

const BLESS: &str = "HAMMERSTEIN_BLESS";

/// The binary's standard output for `args` (which must succeed).
fn help(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_hammerstein"))
        .args(args)
        .env("NO_COLOR", "1")
        .env_remove("COLUMNS")
        .output()
        .expect("the hammerstein binary runs");
    assert!(
        out.status.success(),
        "hammerstein {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("help is UTF-8")
}

/// The command names of the "Commands:" section of the top-level help, in their order
/// (without clap's own `help`).
fn commands(top: &str) -> Vec<String> {
    let mut names = Vec::new();
    let mut inside = false;
    for line in top.lines() {
        if line.starts_with("Commands:") {
            inside = true;
            continue;
        }
        if !inside {
            continue;
        }
        // an entry is indented by two spaces; a wrapped description by more
        let Some(rest) = line.strip_prefix("  ") else {
            break; // blank line or the next section
        };
        if rest.starts_with(' ') {
            continue;
        }
        let name = rest.split_whitespace().next().unwrap_or("");
        if !name.is_empty() && name != "help" {
            names.push(name.to_string());
        }
    }
    names
}

/// The page: an introduction, then one section per command with its help verbatim.
fn page() -> String {
    let top = help(&["--help"]);
    let names = commands(&top);
    assert!(
        !names.is_empty(),
        "no commands found in `hammerstein --help`:\n{top}"
    );
    let mut s = String::new();
    s.push_str("# Command-line reference\n\n");
    s.push_str(
        "Every command of the `hammerstein` binary and each of its options, as the binary \
         itself prints them\n(`hammerstein --help`, `hammerstein COMMAND --help`). The workflow \
         they serve is in [the guide](guide.md).\n\n",
    );
    s.push_str(
        "This page is generated: `tests/cli_docs.rs` fails when it differs from the binary's \
         help, and\n`HAMMERSTEIN_BLESS=1 cargo test --test cli_docs` rewrites it.\n\n",
    );
    s.push_str("Commands:");
    for n in &names {
        s.push_str(&format!(" [`{n}`](#hammerstein-{n})"));
    }
    s.push_str("\n\n## hammerstein\n\n```text\n");
    s.push_str(top.trim_end());
    s.push_str("\n```\n");
    for n in &names {
        s.push_str(&format!("\n## hammerstein {n}\n\n```text\n"));
        s.push_str(help(&[n, "--help"]).trim_end());
        s.push_str("\n```\n");
    }
    s
}

#[test]
fn cli_md_is_the_binarys_help() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("docs/cli.md");
    let want = page();
    if std::env::var_os(BLESS).is_some_and(|v| !v.is_empty() && v != "0") {
        std::fs::write(&path, &want).expect("docs/cli.md is writable");
        return;
    }
    let have = std::fs::read_to_string(&path).unwrap_or_default();
    if have != want {
        let first = have
            .lines()
            .zip(want.lines())
            .position(|(a, b)| a != b)
            .unwrap_or(have.lines().count().min(want.lines().count()));
        panic!(
            "docs/cli.md differs from the binary's --help (first at line {}):\n  page:   {:?}\n  binary: {:?}\n\
             Regenerate it with:  {BLESS}=1 cargo test --test cli_docs",
            first + 1,
            have.lines().nth(first).unwrap_or("<end of file>"),
            want.lines().nth(first).unwrap_or("<end of file>"),
        );
    }
}

#[test]
fn commands_are_read_from_the_help() {
    let top = "Usage: x <COMMAND>\n\nCommands:\n  fit   Fit a model\n        wrapped text\n  demo  Demo\n  help  Print this message\n\nOptions:\n  -h, --help  Print help\n";
    assert_eq!(commands(top), ["fit", "demo"]);
}
