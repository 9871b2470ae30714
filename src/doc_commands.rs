//! The documents' command lines and revision numbers, checked against the
//! code: every `knotsweep ...` command in README.md, ARCHITECTURE.md,
//! BENCHMARKS.md, python/README.md and docs/*.md parses with this binary's
//! flags (a `run` or `snapshots` also passes the parameter table's
//! validation, its start shape file read), the physics revision that
//! README.md and docs/API.md state is the code's, and README.md's claims on
//! the paper's Fig. 1 are docs/VALIDATION.md's numbers (`knotsweep reproduce`'s).
use crate::{Cli, Command};
use clap::Parser;
use clap::error::ErrorKind;
use std::path::{Path, PathBuf};

/// The documents whose commands are checked (CHANGELOG.md is history).
fn documents() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = [
        "README.md",
        "ARCHITECTURE.md",
        "BENCHMARKS.md",
        "python/README.md",
    ]
    .iter()
    .map(PathBuf::from)
    .collect();
    let mut docs: Vec<PathBuf> = std::fs::read_dir("docs")
        .expect("docs/")
        .map(|e| e.expect("a docs/ entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    files.extend(docs);
    files
}

/// The binary's subcommands, the words that make `knotsweep WORD` a command.
const SUBCOMMANDS: [&str; 9] = [
    "validate",
    "run",
    "reproduce",
    "simplified",
    "snapshots",
    "serve",
    "worker",
    "sweep",
    "fit",
];

/// A command found in a document: where, and its arguments after `knotsweep`.
#[derive(Debug)]
struct Found {
    at: String,
    args: Vec<String>,
}

/// The arguments of the command starting at `text` (just after `knotsweep `):
/// shell words (single and double quotes group, and are removed) up to a
/// shell operator, a comment or the end.
fn arguments(text: &str) -> Vec<String> {
    let mut words = Vec::new();
    let (mut word, mut quote, mut started) = (String::new(), None, false);
    for c in text.chars().chain(std::iter::once(' ')) {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), c) => word.push(c),
            (None, '\'' | '"') => (quote, started) = (Some(c), true),
            (None, c) if c.is_whitespace() => {
                if started {
                    if matches!(word.as_str(), "|" | ">" | "&&" | "||" | ";" | "#" | "\\" | "2>&1") {
                        return words;
                    }
                    words.push(std::mem::take(&mut word));
                    started = false;
                }
            }
            (None, c) => {
                word.push(c);
                started = true;
            }
        }
    }
    words
}

/// `knotsweep SUBCOMMAND ...` and `cargo run --release -- SUBCOMMAND ...`
/// commands in `text` (a code span or a line of a code block).
fn commands_in(text: &str, at: &str, found: &mut Vec<Found>) {
    for prefix in ["knotsweep ", "cargo run --release -- ", "cargo run -- "] {
        let mut rest = text;
        while let Some(i) = rest.find(prefix) {
            let before = rest[..i].chars().next_back();
            let after = &rest[i + prefix.len()..];
            rest = after;
            if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '-' || c == '/' || c == '.') {
                continue;
            }
            let args = arguments(after);
            if args.first().is_some_and(|w| SUBCOMMANDS.contains(&w.as_str())) {
                found.push(Found {
                    at: at.to_string(),
                    args,
                });
            }
        }
    }
}

/// Every command of a markdown document: in its code blocks' lines and its
/// inline code spans (which may run over a paragraph's lines).
fn commands(path: &Path) -> Vec<Found> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut found = Vec::new();
    let mut in_block = false;
    let mut paragraph = (String::new(), String::new());
    let spans = |(at, text): &(String, String), found: &mut Vec<Found>| {
        for (i, span) in text.split('`').enumerate() {
            if i % 2 == 1 {
                commands_in(span, at, found);
            }
        }
    };
    for (k, line) in text.lines().enumerate() {
        let at = format!("{}:{}", path.display(), k + 1);
        if line.trim_start().starts_with("```") || line.trim().is_empty() {
            spans(&paragraph, &mut found);
            paragraph = (String::new(), String::new());
            if !line.trim().is_empty() {
                in_block = !in_block;
            }
            continue;
        }
        if in_block {
            commands_in(line, &at, &mut found);
            continue;
        }
        if paragraph.1.is_empty() {
            paragraph.0 = at;
        } else {
            paragraph.1.push(' ');
        }
        paragraph.1.push_str(line);
    }
    spans(&paragraph, &mut found);
    found
}

/// Why a found command does not hold, if it does not.
fn problem(f: &Found) -> Option<String> {
    let argv = std::iter::once("knotsweep".to_string()).chain(f.args.iter().cloned());
    let cli = match Cli::try_parse_from(argv) {
        Ok(cli) => cli,
        // `--help` is a command that works; a bare subcommand in prose names it.
        Err(e) if e.kind() == ErrorKind::DisplayHelp => return None,
        Err(e)
            if f.args.len() == 1
                && matches!(
                    e.kind(),
                    ErrorKind::MissingRequiredArgument | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
                ) =>
        {
            return None;
        }
        Err(e) => return Some(e.to_string().lines().next().unwrap_or_default().to_string()),
    };
    let flags = match cli.command {
        Command::Run(args) => args.params,
        Command::Snapshots(args) => args.params,
        _ => return None,
    };
    let params = match flags.params() {
        Ok(p) => p,
        Err(e) => return Some(format!("{e:#}")),
    };
    params.validate().err().map(|errors| {
        errors
            .iter()
            .map(|e| e.to_string())
            .collect::<Vec<_>>()
            .join("; ")
    })
}

#[test]
fn every_documented_command_parses_and_its_case_is_valid() {
    let found: Vec<Found> = documents().iter().flat_map(|p| commands(p)).collect();
    assert!(found.len() > 40, "commands found: {}", found.len());
    let problems: Vec<String> = (found.iter())
        .filter_map(|f| problem(f).map(|p| format!("{}: knotsweep {}\n  {p}", f.at, f.args.join(" "))))
        .collect();
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn a_broken_command_is_caught() {
    let mut found = Vec::new();
    commands_in(
        "cargo run --release -- run --n 3 --mu -1 | tee log; knotsweep sweep --no-such-flag",
        "here",
        &mut found,
    );
    assert_eq!(found.len(), 2, "{found:?}");
    assert_eq!(found[0].args, ["sweep", "--no-such-flag"]);
    assert_eq!(found[1].args, ["run", "--n", "3", "--mu", "-1"]);
    assert!(problem(&found[0]).is_some(), "an unknown flag");
    assert!(problem(&found[1]).unwrap().contains("mu"), "a value out of range");
    let quoted = arguments(r#"run --loading '[{"pull": {}}, {"hold": {"seconds": 1}}]' --n 3 # a comment"#);
    assert_eq!(
        quoted,
        [
            "run",
            "--loading",
            r#"[{"pull": {}}, {"hold": {"seconds": 1}}]"#,
            "--n",
            "3"
        ]
    );
}

/// The physics revision that README.md and docs/API.md state, every time
/// they state one, is the code's.
#[test]
fn documents_state_the_codes_physics_revision() {
    let current = solver::case::PHYSICS_REVISION.to_string();
    for path in ["README.md", "docs/API.md", "python/README.md"] {
        let text = std::fs::read_to_string(path).expect(path);
        let lower = text.to_lowercase();
        for key in ["physics revision ", "\"physics_revision\": "] {
            for (i, _) in lower.match_indices(key) {
                let digits: String = lower[i + key.len()..]
                    .chars()
                    .take_while(char::is_ascii_digit)
                    .collect();
                assert!(
                    digits.is_empty() || digits == current,
                    "{path} states physics revision {digits}; the code's is {current}"
                );
            }
        }
    }
}

/// `text` with every run of whitespace one space (a claim may break over lines).
fn one_line(text: &str) -> String {
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// README.md says where n = 3 and n = 4 invert against the paper's Fig. 1 in
/// docs/VALIDATION.md's numbers, which `knotsweep reproduce` writes: its
/// check rows give the l_k bar reached and the paper's bracket, and the
/// README's words (inside, outside) follow from them.
#[test]
fn readme_fig1_claims_are_the_validation_numbers() {
    let readme = one_line(&std::fs::read_to_string("README.md").expect("README.md"));
    let validation = std::fs::read_to_string("docs/VALIDATION.md").expect("docs/VALIDATION.md");
    for (n, claim) in [
        (3, "n = 3 inverts {where} the paper's Fig. 1 bracket"),
        (4, "n = 4 {where}"),
    ] {
        let row = (validation.lines())
            .find(|l| l.starts_with(&format!("| n = {n}, h = 1.6 mm: inversion")))
            .unwrap_or_else(|| panic!("docs/VALIDATION.md has no n = {n} row"));
        let bracket = row
            .split("paper Fig. 1: ")
            .nth(1)
            .and_then(|r| r.split("l_k bar ").nth(1))
            .and_then(|r| r.split(';').next())
            .expect("the paper's bracket");
        let (lo, hi) = bracket.split_once('-').expect("lo-hi");
        let (lo, hi): (f64, f64) = (lo.parse().unwrap(), hi.parse().unwrap());
        let got = row
            .split("| l_k bar ")
            .nth(1)
            .and_then(|r| r.split(' ').next())
            .expect("the l_k bar reached");
        let value: f64 = got.parse().unwrap();
        let (where_, number) = if (lo..=hi).contains(&value) {
            ("inside", format!("(l_k bar {got} in {bracket})"))
        } else {
            ("just outside it", format!("(l_k bar {got} against {bracket}"))
        };
        let claim = claim.replace("{where}", where_);
        assert!(
            readme.contains(&format!("{claim} {number}")),
            "README.md should say \"{claim} {number}\" (docs/VALIDATION.md: {row})"
        );
    }
}
