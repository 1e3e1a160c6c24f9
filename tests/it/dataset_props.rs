//! Property tests of the CSV record reader and writer (`dataset`). The number of cases of the
//! reader's properties is raised for the long run by `SEAT_TWIN_FUZZ_CASES` (see `fuzz`).

use crate::fuzz::{Mutation, apply, config, config_scaled, mutation_of};
use proptest::prelude::*;
use seat_twin::dataset::{
    COLUMNS, RecordKind, column_limit, parse_record, parse_record_bytes, read_record, write_csv,
    write_csv_atomic,
};
use std::path::Path;

const FILE: &str = "props/ride.csv";

fn path() -> &'static Path {
    Path::new(FILE)
}

fn kind() -> impl Strategy<Value = RecordKind> {
    prop_oneof![Just(RecordKind::Measured), Just(RecordKind::Excitation)]
}

/// Parses and checks the outcome is a record or an error with a message naming the file.
fn parse_never_panics(text: &str, kind: RecordKind) -> Result<(), TestCaseError> {
    match parse_record(text, path(), kind) {
        Ok(r) => {
            prop_assert!(r.len() >= 2);
            prop_assert!(r.dt > 0.0 && r.dt.is_finite());
            for name in ["t", "v_in", "u", "x", "xdd", "ydd", "p1", "p2"] {
                if let Some(c) = r.column(name) {
                    prop_assert_eq!(c.len(), r.len());
                    prop_assert!(c.iter().all(|v| v.is_finite()));
                }
            }
        }
        Err(e) => {
            let msg = e.to_string();
            prop_assert!(!msg.is_empty());
            prop_assert!(
                msg.starts_with(FILE),
                "message does not name the file: {}",
                msg
            );
        }
    }
    Ok(())
}

/// Finite numbers of every scale within ±1000 (the smallest column bound), including ±0 and
/// subnormals.
fn value() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => -1e3..1e3f64,
        1 => any::<f64>()
            .prop_filter("finite", |v| v.is_finite())
            .prop_map(|v| if v.abs() > 1e3 { 1e3 / v } else { v }),
        1 => Just(0.0),
        1 => Just(-0.0),
        1 => Just(5e-324),
        1 => Just(1e3),
        1 => Just(-1e3),
    ]
}

/// A valid record: kind, rate [Hz], start time [s], header, metadata and rows.
#[derive(Debug, Clone)]
struct Valid {
    kind: RecordKind,
    rate_hz: f64,
    header: Vec<&'static str>,
    metadata: Vec<(String, String)>,
    rows: Vec<Vec<f64>>,
}

impl Valid {
    fn text(&self) -> String {
        let mut out = Vec::new();
        write_csv(
            &mut out,
            &self.header,
            &self.metadata,
            self.rows.clone().into_iter(),
        )
        .expect("a valid record is written");
        String::from_utf8(out).expect("the writer writes UTF-8")
    }
}

fn valid() -> impl Strategy<Value = Valid> {
    (
        kind(),
        0.0..1.0f64,
        -100.0..100.0f64,
        2usize..200,
        proptest::sample::subsequence(
            vec!["v_in", "u", "x", "xdd", "ydd", "p1", "p2", "extra"],
            0..=8,
        ),
        any::<bool>(),
        proptest::collection::vec(("[a-z_]{1,12}", "[!-~]([ -~]{0,20}[!-~])?"), 0..4),
        any::<u64>(),
    )
        .prop_flat_map(
            |(kind, rate_frac, t0, n, optional, pick_x, metadata, seed)| {
                let (lo, hi) = kind.rate_range_hz();
                // Log-uniform over the allowed range.
                let rate_hz = lo * (hi / lo).powf(rate_frac);
                let mut header: Vec<&'static str> = vec!["t"];
                match kind {
                    RecordKind::Measured => header.extend(["v_in", "u"]),
                    RecordKind::Excitation => header.push(if pick_x { "x" } else { "xdd" }),
                }
                for c in optional {
                    if !header.contains(&c) {
                        header.push(c);
                    }
                }
                // Shuffle the column order deterministically from the seed.
                let mut s = seed;
                for i in (1..header.len()).rev() {
                    s = s
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    header.swap(i, (s >> 33) as usize % (i + 1));
                }
                let ncol = header.len();
                let t_col = header.iter().position(|&h| h == "t").unwrap_or(0);
                proptest::collection::vec(proptest::collection::vec(value(), ncol), n).prop_map(
                    move |mut rows| {
                        for (i, row) in rows.iter_mut().enumerate() {
                            row[t_col] = t0 + i as f64 / rate_hz;
                        }
                        Valid {
                            kind,
                            rate_hz,
                            header: header.clone(),
                            metadata: metadata.clone(),
                            rows,
                        }
                    },
                )
            },
        )
}

/// CSV tokens worth inserting.
const CSV_TOKENS: [&str; 19] = [
    "nan", "NaN", "inf", "-inf", "", ",", ",,", "\n", "\r\n", "#", "# k: v\n", "-", "1e999", "\"",
    "t", "x", "\u{feff}", "é", " ",
];

fn mutation() -> impl Strategy<Value = Mutation> {
    mutation_of(&CSV_TOKENS)
}

proptest! {
    #![proptest_config(config(512))]

    #[test]
    fn arbitrary_strings_never_panic(text in any::<String>(), kind in kind()) {
        parse_never_panics(&text, kind)?;
    }

    #[test]
    fn csv_like_strings_never_panic(
        text in "(#[ -~]{0,12}\n)?([tv_inuxdyp12,]{0,20}\n)?([-0-9.eE+,naifNI \r\n#]{0,200})",
        kind in kind(),
    ) {
        parse_never_panics(&text, kind)?;
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..300), kind in kind()) {
        match parse_record_bytes(&bytes, path(), kind) {
            Ok(r) => prop_assert!(r.len() >= 2),
            Err(e) => prop_assert!(e.to_string().starts_with(FILE)),
        }
    }

}

proptest! {
    // Each case builds a valid record of up to 200 rows: a tenth of the long run's cases.
    #![proptest_config(config_scaled(512, 10))]

    #[test]
    fn mutated_valid_files_never_panic(
        v in valid(),
        mutations in proptest::collection::vec(mutation(), 1..6),
        kind in kind(),
    ) {
        let mut bytes = v.text().into_bytes();
        for m in &mutations {
            apply(&mut bytes, m);
        }
        match parse_record_bytes(&bytes, path(), kind) {
            Ok(r) => prop_assert!(r.len() >= 2),
            Err(e) => prop_assert!(e.to_string().starts_with(FILE)),
        }
        parse_never_panics(&String::from_utf8_lossy(&bytes), kind)?;
    }

    #[test]
    fn valid_records_read_back_exactly(v in valid()) {
        let text = v.text();
        let r = match parse_record(&text, path(), v.kind) {
            Ok(r) => r,
            Err(e) => return Err(TestCaseError::fail(format!("{e}\n{text}"))),
        };
        prop_assert_eq!(r.len(), v.rows.len());
        prop_assert!((r.sample_rate_hz() / v.rate_hz - 1.0).abs() < 1e-6,
            "rate {} vs {}", r.sample_rate_hz(), v.rate_hz);
        prop_assert_eq!(&r.metadata, &v.metadata);
        for (j, name) in v.header.iter().enumerate() {
            let col = r.column(name);
            if *name == "extra" {
                prop_assert!(col.is_none());
                continue;
            }
            let col = col.ok_or_else(|| TestCaseError::fail(format!("column {name} missing")))?;
            for (i, row) in v.rows.iter().enumerate() {
                prop_assert_eq!(col[i].to_bits(), row[j].to_bits(), "{}[{}]", name, i);
            }
        }
        let unknown = r.warnings.iter().filter(|w| w.contains("unknown column")).count();
        prop_assert_eq!(unknown, usize::from(v.header.contains(&"extra")));
    }
}

proptest! {
    // Writes and syncs a file per case: not part of the long run.
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn atomic_write_then_read_round_trips(v in valid()) {
        let dir = tempfile::tempdir().expect("temporary directory");
        let file = dir.path().join("rec.csv");
        write_csv_atomic(&file, &v.header, &v.metadata, v.rows.clone().into_iter())
            .expect("written");
        let r = read_record(&file, v.kind).map_err(|e| TestCaseError::fail(e.to_string()))?;
        prop_assert_eq!(r.len(), v.rows.len());
        let t_col = v.header.iter().position(|&h| h == "t").unwrap_or(0);
        for (i, row) in v.rows.iter().enumerate() {
            prop_assert_eq!(r.t[i].to_bits(), row[t_col].to_bits());
        }
    }
}

proptest! {
    // Writes a file per case: not part of the long run.
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Issue 21, item 7: a file is read line by line from disk, text in memory is split at
    /// once; both give the same record or the same message, on valid and on broken files.
    #[test]
    fn a_file_read_line_by_line_equals_its_bytes_parsed_at_once(
        v in valid(),
        mutations in proptest::collection::vec(mutation(), 0..4),
        bom in any::<bool>(),
        crlf in any::<bool>(),
    ) {
        let mut bytes = v.text().into_bytes();
        for m in &mutations {
            apply(&mut bytes, m);
        }
        if crlf {
            bytes = String::from_utf8_lossy(&bytes).replace('\n', "\r\n").into_bytes();
        }
        if bom {
            bytes.splice(0..0, "\u{feff}".bytes());
        }
        let dir = tempfile::tempdir().expect("temporary directory");
        let file = dir.path().join("ride.csv");
        std::fs::write(&file, &bytes).expect("written");
        let from_file = read_record(&file, v.kind).map_err(|e| e.to_string());
        let at_once = parse_record_bytes(&bytes, &file, v.kind).map_err(|e| e.to_string());
        prop_assert_eq!(from_file, at_once);
    }
}

/// A record with one cell replaced by `cell` in column `col` at data row `row`.
fn with_cell(col: usize, row: usize, cell: &str) -> (String, &'static str, usize) {
    let name = COLUMNS[col];
    let mut header: Vec<&str> = vec!["t", "v_in", "u"];
    if !header.contains(&name) {
        header.push(name);
    }
    let j = header.iter().position(|h| *h == name).unwrap();
    let mut text = header.join(",");
    text.push('\n');
    for i in 0..6 {
        let mut cells: Vec<String> = header
            .iter()
            .map(|h| {
                if *h == "t" {
                    format!("{}", i as f64 / 1000.0)
                } else {
                    "0".into()
                }
            })
            .collect();
        if i == row {
            cells[j] = cell.to_string();
        }
        text.push_str(&cells.join(","));
        text.push('\n');
    }
    (text, name, row + 2)
}

proptest! {
    #![proptest_config(config(512))]

    /// A cell beyond its column's bound is an error naming the file, line and column; one
    /// within it is read as written.
    #[test]
    fn cells_beyond_their_column_bound_are_refused_by_line_and_column(
        col in 1usize..COLUMNS.len(),
        row in 1usize..6,
        factor in prop_oneof![0.0..=1.0f64, 1.0..1e290f64],
        negative in any::<bool>(),
    ) {
        let limit = column_limit(COLUMNS[col]);
        let v = limit * factor * if negative { -1.0 } else { 1.0 };
        let (text, name, line) = with_cell(col, row, &format!("{v:e}"));
        match parse_record(&text, path(), RecordKind::Measured) {
            Ok(r) => {
                prop_assert!(v.abs() <= limit, "{} = {} accepted", name, v);
                prop_assert_eq!(r.column(name).unwrap()[row], v);
            }
            Err(e) => {
                prop_assert!(v.abs() > limit, "{} = {} refused: {}", name, v, e);
                let msg = e.to_string();
                let expected = format!("{FILE}: line {line}, column \"{name}\"");
                prop_assert!(msg.starts_with(&expected), "{}", msg);
                prop_assert!(msg.contains("is beyond"), "{}", msg);
            }
        }
    }

    /// A row with a field more or less than the header names a column of the header.
    #[test]
    fn a_wrong_field_count_names_a_header_column(
        extra in prop_oneof![Just(-2i32), Just(-1), Just(1), Just(3)],
        row in 0usize..5,
    ) {
        let header = ["t", "x", "xdd", "note"];
        let mut text = header.join(",") + "\n";
        for i in 0..5 {
            let n = if i == row { (4 + extra) as usize } else { 4 };
            let cells: Vec<String> = (0..n)
                .map(|j| if j == 0 { format!("{}", i as f64 / 100.0) } else { "1".into() })
                .collect();
            text.push_str(&cells.join(","));
            text.push('\n');
        }
        let e = parse_record(&text, path(), RecordKind::Excitation).unwrap_err();
        let msg = e.to_string();
        let named = if extra < 0 { header[(4 + extra) as usize] } else { "note" };
        prop_assert!(
            msg.starts_with(&format!("{FILE}: line {}: ", row + 2)),
            "{}", msg
        );
        prop_assert!(msg.contains(&format!("column \"{named}\"")), "{}", msg);
        prop_assert!(!msg.contains("\"-\""), "{}", msg);
    }
}
