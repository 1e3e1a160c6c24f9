//! Property tests ("fuzzing") of the preset reader and the command line's parsing and
//! validation; the CSV reader's are in `dataset_props`. None may panic, on any input.
//!
//! `cargo test` runs a few hundred cases per property. The long run sets the number of cases
//! of every parser property with `SEAT_TWIN_FUZZ_CASES` (see [`cases`]; the two CSV
//! properties that build whole valid records get a tenth of it):
//!
//! ```text
//! SEAT_TWIN_FUZZ_CASES=1000000 cargo test --no-default-features --test it -- \
//!     fuzz:: dataset_props:: --test-threads 2
//! ```

use clap::Parser;
use proptest::prelude::*;
use seat_twin::cli::{self, Cli, Command};
use seat_twin::preset::Preset;
use std::path::Path;

/// Cases per property: `SEAT_TWIN_FUZZ_CASES` if set (the long run), else `default`.
pub(crate) fn cases(default: u32) -> u32 {
    std::env::var("SEAT_TWIN_FUZZ_CASES")
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(default)
}

pub(crate) fn config(default: u32) -> ProptestConfig {
    config_scaled(default, 1)
}

/// [`config`] for a property whose cases are `div` times as costly (each builds a record of
/// up to 200 rows): the long run gives it a `div`-th of the cases.
pub(crate) fn config_scaled(default: u32, div: u32) -> ProptestConfig {
    let cases = match std::env::var("SEAT_TWIN_FUZZ_CASES").ok() {
        Some(_) => (cases(default) / div.max(1)).max(1),
        None => default,
    };
    ProptestConfig {
        cases,
        // No regression files in the tree: a failure prints its minimal case.
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

// ---------------------------------------------------------------------------------------------
// Presets

const FILE: &str = "fuzz/preset.toml";

fn file() -> &'static Path {
    Path::new(FILE)
}

/// Checks one outcome of the preset reader: a preset whose parameters are valid, or an error
/// whose message names the file.
fn preset_outcome(r: Result<Preset, seat_twin::preset::PresetError>) -> Result<(), TestCaseError> {
    match r {
        Ok(p) => prop_assert!(p.params.validate().is_ok()),
        Err(e) => {
            let msg = e.to_string();
            prop_assert!(
                msg.starts_with(FILE),
                "message does not name the file: {}",
                msg
            );
            prop_assert!(msg.len() < 2000, "message of {} bytes", msg.len());
        }
    }
    Ok(())
}

/// `(table, key, value)` of every key of the paper's preset, from its own TOML text.
fn known_keys() -> Vec<(String, String, toml::Value)> {
    let text = Preset::paper().to_toml();
    let doc: toml::Table = toml::from_str(&text).expect("the paper's preset is TOML");
    let mut out = Vec::new();
    fn walk(prefix: &str, t: &toml::Table, out: &mut Vec<(String, String, toml::Value)>) {
        for (k, v) in t {
            match v {
                toml::Value::Table(sub) => {
                    let p = if prefix.is_empty() {
                        k.clone()
                    } else {
                        format!("{prefix}.{k}")
                    };
                    walk(&p, sub, out);
                }
                _ => out.push((prefix.to_string(), k.clone(), v.clone())),
            }
        }
    }
    walk("", &doc, &mut out);
    out
}

/// TOML value text of every kind and scale, valid or not.
fn toml_value() -> impl Strategy<Value = String> {
    prop_oneof![
        any::<f64>().prop_map(|v| format!("{v:?}")),
        (-1e3..1e3f64).prop_map(|v| format!("{v}")),
        any::<i64>().prop_map(|v| v.to_string()),
        Just("nan".to_string()),
        Just("-inf".to_string()),
        Just("1e400".to_string()),
        any::<bool>().prop_map(|b| b.to_string()),
        "\"[ -~]{0,12}\"",
        Just("[1, 2.5]".to_string()),
        Just("{ a = 1 }".to_string()),
        Just("1979-05-27T07:32:00Z".to_string()),
        Just("\"exponential\"".to_string()),
        Just("\"rk4\"".to_string()),
        "[ -~]{0,8}",
    ]
}

#[derive(Debug, Clone)]
struct Doc {
    entries: Vec<(String, String, String)>,
    inline: bool,
}

fn doc(keys: Vec<(String, String, toml::Value)>) -> impl Strategy<Value = Doc> {
    let n = keys.len();
    (
        proptest::collection::vec((0..n + 2, "[a-z_]{1,10}", toml_value()), 0..8),
        "[a-z_]{1,10}",
        any::<bool>(),
    )
        .prop_map(move |(picks, name, inline)| Doc {
            entries: picks
                .into_iter()
                .map(|(i, key, v)| match keys.get(i) {
                    Some((t, k, _)) => (t.clone(), k.clone(), v),
                    None if i == n => ("body".to_string(), key, v),
                    None => (key.clone(), name.clone(), v),
                })
                .collect(),
            inline,
        })
}

impl Doc {
    fn text(&self) -> String {
        let mut s = String::new();
        for (t, k, v) in &self.entries {
            if self.inline || t.is_empty() {
                if t.is_empty() {
                    s.push_str(&format!("{k} = {v}\n"));
                } else {
                    s.push_str(&format!("{t}.{k} = {v}\n"));
                }
            } else {
                s.push_str(&format!("[{t}]\n{k} = {v}\n"));
            }
        }
        s
    }
}

/// One edit of a file's bytes (the mutation fuzzers of the preset and dataset readers).
#[derive(Debug, Clone)]
pub(crate) enum Mutation {
    Flip { at: usize, bits: u8 },
    Truncate { at: usize },
    Insert { at: usize, what: &'static str },
    Delete { at: usize, len: usize },
}

/// Preset-reader tokens worth inserting.
const PRESET_TOKENS: [&str; 21] = [
    "nan", "inf", "-", "1e999", "\"", "'", "[", "]", "[[", "=", "\n", "{", "}", ",", ".", "#",
    "\0", "é", "0x1F", "true", "\"\"\"",
];

/// A random edit: a flipped byte, a truncation, one of `tokens` inserted, or a deletion.
pub(crate) fn mutation_of(tokens: &[&'static str]) -> impl Strategy<Value = Mutation> + use<> {
    let token = proptest::sample::select(tokens.to_vec());
    prop_oneof![
        (any::<usize>(), 1u8..=255).prop_map(|(at, bits)| Mutation::Flip { at, bits }),
        any::<usize>().prop_map(|at| Mutation::Truncate { at }),
        (any::<usize>(), token).prop_map(|(at, what)| Mutation::Insert { at, what }),
        (any::<usize>(), 1usize..20).prop_map(|(at, len)| Mutation::Delete { at, len }),
    ]
}

fn mutation() -> impl Strategy<Value = Mutation> {
    mutation_of(&PRESET_TOKENS)
}

/// Applies an edit (positions taken modulo the length, so every edit applies).
pub(crate) fn apply(bytes: &mut Vec<u8>, m: &Mutation) {
    let n = bytes.len();
    match *m {
        Mutation::Flip { at, bits } => {
            if n > 0 {
                bytes[at % n] ^= bits;
            }
        }
        Mutation::Truncate { at } => bytes.truncate(at % (n + 1)),
        Mutation::Insert { at, what } => {
            let at = at % (n + 1);
            bytes.splice(at..at, what.bytes());
        }
        Mutation::Delete { at, len } => {
            let at = at % (n + 1);
            bytes.drain(at..(at + len).min(n));
        }
    }
}

proptest! {
    #![proptest_config(config(256))]

    #[test]
    fn preset_reader_never_panics_on_any_text(text in any::<String>()) {
        preset_outcome(Preset::from_toml(&text, file()))?;
    }

    #[test]
    fn preset_reader_never_panics_on_any_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        preset_outcome(Preset::from_bytes(&bytes, file()))?;
    }

    #[test]
    fn preset_reader_never_panics_on_toml_like_documents(d in doc(known_keys())) {
        preset_outcome(Preset::from_toml(&d.text(), file()))?;
    }

    #[test]
    fn preset_reader_never_panics_on_mutated_presets(
        mutations in proptest::collection::vec(mutation(), 1..6),
    ) {
        let mut bytes = Preset::paper().to_toml().into_bytes();
        for m in &mutations {
            apply(&mut bytes, m);
        }
        preset_outcome(Preset::from_bytes(&bytes, file()))?;
    }

    /// A value of the wrong type is an error that names its dotted key.
    #[test]
    fn a_value_of_the_wrong_type_names_its_key(
        i in any::<proptest::sample::Index>(),
        wrong in prop_oneof![
            Just("\"text\""), Just("[1, 2]"), Just("{ a = 1 }"), Just("1979-05-27")
        ],
        inline in any::<bool>(),
    ) {
        let keys = known_keys();
        let (table, key, value) = &keys[i.index(keys.len())];
        // A string key takes a string: give it an array instead (no rejected cases, so the
        // long run never hits proptest's reject limit).
        let wrong = if matches!(value, toml::Value::String(_)) && wrong == "\"text\"" {
            "[1, 2]"
        } else {
            wrong
        };
        let text = match (table.is_empty(), inline) {
            (true, _) => format!("{key} = {wrong}\n"),
            (false, true) => format!("{table}.{key} = {wrong}\n"),
            (false, false) => format!("[{table}]\n{key} = {wrong}\n"),
        };
        let dotted = if table.is_empty() { key.clone() } else { format!("{table}.{key}") };
        match Preset::from_toml(&text, file()) {
            Ok(_) => return Err(TestCaseError::fail(format!("accepted: {text}"))),
            Err(e) => {
                let msg = e.to_string();
                prop_assert!(msg.contains(&format!("`{dotted}`")), "{}: {}", text, msg);
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Command line

/// A numeric option's value as typed: numbers of every sign and scale, in several spellings,
/// and some that are not numbers.
fn number_text() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => any::<f64>().prop_map(|v| format!("{v}")),
        4 => (-2e5..2e5f64).prop_map(|v| format!("{v}")),
        2 => (-50.0..50.0f64).prop_map(|v| format!("{v:e}")),
        2 => (-100i64..100_000).prop_map(|v| v.to_string()),
        1 => proptest::sample::select(vec![
            "nan", "NaN", "inf", "-inf", "infinity", "1e309", "-1e309", "0", "-0", "", " ", "1,2",
            "--", "-", "1e", "0x10", "1_000", "+5", ".5", "5.", "abc", "-1,2", "1e-300",
        ])
        .prop_map(str::to_string),
    ]
}

/// The numeric options of each subcommand and their documented ranges, from the help text
/// and README (the test's own reference, not the code's constants).
fn documented_range(sub: &str, opt: &str, scenario_random: bool) -> Option<(f64, f64, bool)> {
    // (min, max, min exclusive)
    match (sub, opt) {
        ("simulate", "--rate") => Some((1.0, 100_000.0, false)),
        ("simulate", "--duration") => {
            Some((1e-3, if scenario_random { 3600.0 } else { 36_000.0 }, false))
        }
        ("simulate", "--freq" | "--f0" | "--f1") => Some((0.01, 1000.0, false)),
        ("simulate", "--amp") => Some((0.0, 100.0, false)),
        ("bode", "--amp") => Some((0.0, 100.0, true)),
        (_, "--freqs") => Some((0.01, 1000.0, false)),
        _ => None,
    }
}

fn in_range(v: f64, (lo, hi, open): (f64, f64, bool)) -> bool {
    v.is_finite() && v <= hi && if open { v > lo } else { v >= lo }
}

#[derive(Debug, Clone)]
struct Argv {
    sub: &'static str,
    opts: Vec<(&'static str, String, bool)>,
}

impl Argv {
    fn args(&self) -> Vec<String> {
        let mut v = vec!["seat-twin".to_string(), self.sub.to_string()];
        match self.sub {
            "simulate" => v.extend(["--model", "twin", "--out", "o.csv"].map(String::from)),
            "bode" | "transmissibility" => {
                v.extend(["--model", "linear", "--out", "o.csv"].map(String::from));
                if !self.opts.iter().any(|(o, _, _)| *o == "--freqs") {
                    v.extend(["--freqs", "1"].map(String::from));
                }
            }
            _ => {}
        }
        for (o, val, eq) in &self.opts {
            if *eq {
                v.push(format!("{o}={val}"));
            } else {
                v.push(o.to_string());
                v.push(val.clone());
            }
        }
        v
    }
}

fn argv() -> impl Strategy<Value = Argv> {
    let sub = proptest::sample::select(vec!["simulate", "bode", "transmissibility", "report"]);
    let opt = proptest::sample::select(vec![
        "--rate",
        "--duration",
        "--freq",
        "--amp",
        "--f0",
        "--f1",
        "--freqs",
        "--scenario",
        "--seed",
        "--bogus",
    ]);
    let value = prop_oneof![
        4 => number_text(),
        1 => proptest::collection::vec(number_text(), 1..4).prop_map(|v| v.join(",")),
        1 => proptest::sample::select(vec!["cycloid", "random", "sine", "chirp", "x"])
            .prop_map(str::to_string),
    ];
    (
        sub,
        proptest::collection::vec((opt, value, any::<bool>()), 0..6),
    )
        .prop_map(|(sub, opts)| Argv { sub, opts })
}

/// Parses and validates `args` as the binary does; `Ok` when both accept.
fn parse_and_validate(args: &[String]) -> Result<Command, String> {
    let cli = Cli::try_parse_from(args).map_err(|e| e.to_string())?;
    let cmd = cli.command.ok_or_else(|| "no subcommand".to_string())?;
    cli::validate(&cmd).map_err(|e| e.to_string())?;
    Ok(cmd)
}

/// Every numeric option of an accepted command within its documented range.
fn check_accepted(cmd: &Command) -> Result<(), TestCaseError> {
    match cmd {
        Command::Simulate(cli::SimulateArgs {
            scenario,
            duration,
            freq,
            amp,
            f0,
            f1,
            rate,
            ..
        }) => {
            let random = *scenario == Some(cli::ScenarioArg::Random);
            let r = |o| documented_range("simulate", o, random).expect("documented");
            prop_assert!(in_range(*rate, r("--rate")), "rate {}", rate);
            if let Some(d) = duration {
                prop_assert!(in_range(*d, r("--duration")), "duration {}", d);
            }
            for (name, v) in [("--freq", freq), ("--amp", amp), ("--f0", f0), ("--f1", f1)] {
                if let Some(v) = v {
                    prop_assert!(in_range(*v, r(name)), "{} {}", name, v);
                }
            }
        }
        Command::Bode(cli::BodeArgs { amp, sweep, .. }) => {
            prop_assert!(in_range(
                *amp,
                documented_range("bode", "--amp", false).unwrap()
            ));
            prop_assert!(!sweep.freqs.is_empty());
            for f in &sweep.freqs {
                prop_assert!(in_range(
                    *f,
                    documented_range("bode", "--freqs", false).unwrap()
                ));
            }
        }
        Command::Transmissibility(cli::TransmissibilityArgs { sweep, .. }) => {
            prop_assert!(!sweep.freqs.is_empty());
            for f in &sweep.freqs {
                let r = documented_range("transmissibility", "--freqs", false).unwrap();
                prop_assert!(in_range(*f, r));
            }
        }
        _ => {}
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(512))]

    /// Any command line: parsed and validated without a panic; what is accepted is within the
    /// documented ranges; what is refused has a message.
    #[test]
    fn command_lines_never_panic_and_accept_only_documented_ranges(a in argv()) {
        match parse_and_validate(&a.args()) {
            Ok(cmd) => check_accepted(&cmd)?,
            Err(msg) => prop_assert!(!msg.trim().is_empty()),
        }
    }

    /// One numeric option, typed as `--opt V` or `--opt=V`: accepted exactly when V is a
    /// number in the documented range; a number out of range (negative ones included) gets
    /// the range message naming the option, never clap's "unexpected argument".
    #[test]
    fn one_numeric_option_is_accepted_exactly_in_its_range(
        which in proptest::sample::select(vec![
            ("simulate", "--rate"), ("simulate", "--duration"), ("simulate", "--freq"),
            ("simulate", "--amp"), ("simulate", "--f0"), ("simulate", "--f1"),
            ("bode", "--amp"), ("bode", "--freqs"), ("transmissibility", "--freqs"),
        ]),
        text in number_text(),
        eq in any::<bool>(),
    ) {
        let (sub, opt) = which;
        let a = Argv { sub, opts: vec![(opt, text.clone(), eq)] };
        let range = documented_range(sub, opt, false).expect("documented");
        let result = parse_and_validate(&a.args());
        // The reference: Rust's own f64 syntax (what clap uses), then the range.
        let number = text.parse::<f64>().ok();
        let list: Option<Vec<f64>> = (opt == "--freqs")
            .then(|| text.split(',').map(|t| t.parse::<f64>().ok()).collect())
            .flatten();
        let expected_ok = match (opt, number, &list) {
            ("--freqs", _, Some(l)) => l.iter().all(|&f| in_range(f, range)),
            (_, Some(v), _) => in_range(v, range),
            _ => false,
        };
        prop_assert_eq!(result.is_ok(), expected_ok, "{} {} {:?}: {:?}", sub, opt, text, result.as_ref().err());
        let is_number = number.is_some() || list.is_some();
        if let Err(msg) = &result
            && is_number
        {
            prop_assert!(msg.contains(opt), "{} {:?}: {}", opt, text, msg);
            prop_assert!(msg.contains("is outside the allowed range"), "{} {:?}: {}", opt, text, msg);
            prop_assert!(msg.len() < 300, "{}", msg);
        }
    }
}
