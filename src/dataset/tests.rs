//! Tests of reading, checking and writing records.

use super::error::{fmt_num, sig};
use super::lines::LineMap;
use super::read::parse_with_row_limit;
use super::*;
use std::fmt::Write as _;
use std::fs::File;
use std::io;
use std::path::Path;

fn p() -> &'static Path {
    Path::new("ride.csv")
}

fn err(text: &str, kind: RecordKind) -> DatasetError {
    match parse_record(text, p(), kind) {
        Ok(r) => panic!("expected an error, got a record of {} rows", r.len()),
        Err(e) => e,
    }
}

const GOOD: &str = "# experiment: sine 5 Hz 0.72 V\n# sample_rate_hz: 1000\n\
    t,v_in,u,x,xdd,ydd\n\
    0.000,0.72,0,1.83747616e-05,-0.097796809,0.197458573\n\
    0.001,0.72,0.01,1e-5,0.01,0.2\n\
    0.002,0.72,0.02,2e-5,0.02,0.3\n\
    0.003,0.72,0.03,3e-5,0.03,0.4\n";

#[test]
fn parses_the_example() {
    let r = parse_record(GOOD, p(), RecordKind::Measured).unwrap();
    assert_eq!(r.len(), 4);
    assert!(!r.is_empty());
    assert!((r.sample_rate_hz() - 1000.0).abs() < 1e-6);
    assert!((r.duration_s() - 0.003).abs() < 1e-12);
    assert_eq!(r.metadata_value("experiment"), Some("sine 5 Hz 0.72 V"));
    assert_eq!(r.metadata_value("sample_rate_hz"), Some("1000"));
    assert_eq!(r.metadata_value("nope"), None);
    assert_eq!(r.x.as_ref().unwrap()[0], 1.83747616e-05);
    assert_eq!(r.ydd.as_ref().unwrap()[3], 0.4);
    assert!(r.p1.is_none() && r.p2.is_none());
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    assert_eq!(r.column("u"), Some(&[0.0, 0.01, 0.02, 0.03][..]));
    let e = parse_record(GOOD, p(), RecordKind::Excitation).unwrap();
    assert_eq!(e.len(), 4);
}

#[test]
fn crlf_bom_blank_lines_padding_any_order_and_unknown_columns() {
    let text = "\u{feff}# a: 1\r\n\r\n#plain comment\r\n xdd , t ,foo\r\n\r\n5, 0.5 ,bar\r\n1,0.6,\r\n\r\n# late\r\n2,0.7,x\r\n";
    let r = parse_record(text, p(), RecordKind::Excitation).unwrap();
    assert_eq!(r.t, vec![0.5, 0.6, 0.7]);
    assert_eq!(r.xdd, Some(vec![5.0, 1.0, 2.0]));
    assert_eq!(r.metadata, vec![("a".to_string(), "1".to_string())]);
    assert_eq!(r.warnings.len(), 2, "{:?}", r.warnings);
    assert!(r.warnings[0].contains("unknown column \"foo\" (field 3) ignored"));
    assert!(r.warnings[1].contains("1 comment line after the header skipped (first at line 9)"));
}

#[test]
fn io_error_names_the_file() {
    let e = read_record(Path::new("/nonexistent/ride.csv"), RecordKind::Measured).unwrap_err();
    assert!(matches!(e, DatasetError::Io { .. }));
    assert!(
        e.to_string()
            .starts_with("/nonexistent/ride.csv: cannot read"),
        "{e}"
    );
}

#[test]
fn empty_files() {
    for text in ["", "\n\n", "# a: b\n# c\n\n"] {
        let e = err(text, RecordKind::Measured);
        assert!(matches!(e, DatasetError::Empty { .. }), "{e}");
        assert_eq!(
            e.to_string(),
            "ride.csv: no header row (the file has only comments or blank lines)"
        );
    }
    let e = err("# a: b\nt,v_in,u\n\n", RecordKind::Measured);
    assert!(matches!(e, DatasetError::Empty { .. }));
    assert_eq!(
        e.to_string(),
        "ride.csv: no data rows after the header (line 2)"
    );
}

#[test]
fn missing_columns() {
    let e = err("# x\nt,v_in,x\n0,0,0\n", RecordKind::Measured);
    assert!(matches!(e, DatasetError::MissingColumn { .. }));
    assert_eq!(
        e.to_string(),
        "ride.csv: line 2: missing column \"u\" (a measured record needs t, v_in and u); \
         the header has \"t\", \"v_in\", \"x\""
    );
    let e = err("t,v_in,u\n0,0,0\n", RecordKind::Excitation);
    assert_eq!(
        e.to_string(),
        "ride.csv: line 1: missing column \"x\" or \"xdd\" (an excitation record needs t and \
         at least one of x, xdd); the header has \"t\", \"v_in\", \"u\""
    );
    let e = err("0,1,2\n1,1,2\n", RecordKind::Excitation);
    assert!(e.to_string().contains("missing column \"t\""), "{e}");
    assert!(e.to_string().contains("is the header row missing?"), "{e}");
}

#[test]
fn duplicate_column() {
    let e = err("# m: 1\nt,x,xdd,x\n0,0,0,0\n", RecordKind::Excitation);
    assert!(matches!(e, DatasetError::DuplicateColumn { .. }));
    assert_eq!(
        e.to_string(),
        "ride.csv: line 2: column \"x\" appears twice in the header (fields 2 and 4)"
    );
    // A very wide header is handled in linear time.
    let wide: Vec<String> = (0..200_000).map(|i| format!("c{i}")).collect();
    let e = err(
        &format!("t,{},c7\n", wide.join(",")),
        RecordKind::Excitation,
    );
    assert!(e.to_string().contains("(fields 9 and 200002)"), "{e}");
    // Unknown names may not repeat either.
    let e = err("t,x,foo,foo\n0,0,0,0\n", RecordKind::Excitation);
    assert!(matches!(e, DatasetError::DuplicateColumn { .. }), "{e}");
}

#[test]
fn parse_errors_name_line_and_column() {
    let mut text = String::from("# a: 1\n\nt,v_in,u,x,xdd,ydd\n");
    for i in 0..10 {
        let ydd = if i == 7 {
            "abc".to_string()
        } else {
            "0.5".into()
        };
        text.push_str(&format!("{}.{:03},1,2,3,4,{ydd}\n", i / 1000, i % 1000));
    }
    let e = err(&text, RecordKind::Measured);
    assert!(matches!(e, DatasetError::Parse { .. }));
    assert_eq!(
        e.to_string(),
        "ride.csv: line 11, column \"ydd\": \"abc\" is not a number"
    );

    let cases = [
        (
            "t,x\n0,1\n0.1,nan\n",
            "line 3, column \"x\": \"nan\" is not a finite number",
        ),
        (
            "t,x\n0,1\n0.1,-inf\n",
            "line 3, column \"x\": \"-inf\" is not a finite number",
        ),
        (
            "t,x\n0,1\n0.1,1e999\n",
            "line 3, column \"x\": \"1e999\" is not a finite number",
        ),
        (
            "t,x\n0,1\n0.1,\n",
            "line 3, column \"x\": \"\" is empty; a number is expected",
        ),
        (
            "t,x\n0,1\n0.1, \n",
            "line 3, column \"x\": \"\" is empty; a number is expected",
        ),
        (
            "t,x\n0,1\nNaN,1\n",
            "line 3, column \"t\": \"NaN\" is not a finite number",
        ),
        (
            "t,x\n0,1\n0.1,2e3\n",
            "line 3, column \"x\": \"2e3\" is beyond ±1000 m, the bound of column \"x\" \
             (SI units)",
        ),
        (
            "t,x\n0,1\n-1e10,2\n",
            "line 3, column \"t\": \"-1e10\" is beyond ±1e9 s, the bound of column \"t\" \
             (SI units)",
        ),
    ];
    for (text, msg) in cases {
        let e = err(text, RecordKind::Excitation);
        assert!(matches!(e, DatasetError::Parse { .. }), "{e}");
        assert_eq!(e.to_string(), format!("ride.csv: {msg}"));
    }
    let field_counts = [
        (
            "t,x\n0,1\n0.1,1,2\n",
            "line 3: fields past the last column \"x\" are not expected: the row \"0.1,1,2\" \
             has 3 fields, the header (line 1) has 2",
        ),
        (
            "t,x\n0,1\n0.1\n",
            "line 3: column \"x\" is missing: the row \"0.1\" has 1 field, the header \
             (line 1) has 2",
        ),
        (
            "t,x,note\n0,1,a\n0.1,2,b,4,5\n",
            "line 3: fields past the last column \"note\" are not expected: the row \
             \"0.1,2,b,4,5\" has 5 fields, the header (line 1) has 3",
        ),
    ];
    for (text, msg) in field_counts {
        let e = err(text, RecordKind::Excitation);
        assert!(matches!(e, DatasetError::FieldCount { .. }), "{e}");
        assert_eq!(e.to_string(), format!("ride.csv: {msg}"));
    }
    // Long cells are shortened in the message.
    let long = "z".repeat(10_000);
    let e = err(&format!("t,x\n0,1\n0.1,{long}\n"), RecordKind::Excitation);
    assert!(e.to_string().len() < 200, "{e}");
}

#[test]
fn many_unknown_columns_give_few_warnings() {
    let names: Vec<String> = (0..25).map(|i| format!("c{i}")).collect();
    let text = format!(
        "t,{},x\n0,{z},1\n0.1,{z},2\n",
        names.join(","),
        z = ["0"; 25].join(",")
    );
    let r = parse_record(&text, p(), RecordKind::Excitation).unwrap();
    assert_eq!(r.warnings.len(), 11, "{:?}", r.warnings);
    assert!(r.warnings[9].contains("unknown column \"c9\" (field 11)"));
    assert_eq!(r.warnings[10], "line 1: 15 more unknown columns ignored");
}

#[test]
fn unknown_columns_are_not_read() {
    let r = parse_record("t,note,x\n0,hello,1\n0.1,,2\n", p(), RecordKind::Excitation).unwrap();
    assert_eq!(r.x, Some(vec![1.0, 2.0]));
    assert_eq!(r.warnings.len(), 1);
}

#[test]
fn quoted_cells_are_accepted() {
    let r = parse_record(
        "\"t\",\"x\"\n\"0\",\"1\"\n0.1,2\n",
        p(),
        RecordKind::Excitation,
    )
    .unwrap();
    assert_eq!(r.t, vec![0.0, 0.1]);
    assert_eq!(r.x, Some(vec![1.0, 2.0]));
}

#[test]
fn time_errors() {
    let e = err("t,x\n# c\n0,0\n0.1,0\n0.1,0\n", RecordKind::Excitation);
    assert!(matches!(e, DatasetError::Time { .. }));
    assert_eq!(
        e.to_string(),
        "ride.csv: line 5, column \"t\": t = 0.1 s is not after the previous sample's t = 0.1 s (line 4); \
         t must be strictly increasing"
    );
    let e = err("t,x\n0.2,0\n0.1,0\n", RecordKind::Excitation);
    assert!(
        e.to_string()
            .starts_with("ride.csv: line 3, column \"t\": t = 0.1 s is not after"),
        "{e}"
    );

    // A missing sample: the step from 0.003 to 0.005 at line 8 (blank and comment lines
    // in between are counted).
    let text =
        "# c\nt,v_in,u\n0.000,0,0\n0.001,0,0\n\n0.002,0,0\n0.003,0,0\n# x\n0.005,0,0\n0.006,0,0\n";
    let e = err(text, RecordKind::Measured);
    assert!(matches!(e, DatasetError::Time { line: 9, .. }), "{e:?}");
    assert_eq!(
        e.to_string(),
        "ride.csv: line 9, column \"t\": the step from t = 0.003 s (line 7) to t = 0.005 s is 0.002 s, \
         but the record's step (the median) is 0.001 s ± 1 %: the record is not uniformly \
         sampled (a missing, repeated or shifted sample?)"
    );
    let e = err("t,x\n0,0\n", RecordKind::Excitation);
    assert_eq!(
        e.to_string(),
        "ride.csv: line 2: only one data row; at least two are needed to find the sample rate"
    );
}

#[test]
fn rounded_times_are_uniform_enough() {
    // 3 kHz printed to 1 µs: steps of 333 and 334 µs (0.3 % apart).
    let mut text = String::from("t,v_in,u\n");
    for i in 0..3000 {
        text.push_str(&format!("{:.6},0,0\n", i as f64 / 3000.0));
    }
    let r = parse_record(&text, p(), RecordKind::Measured).unwrap();
    assert!((r.sample_rate_hz() - 3000.0).abs() < 10.0);
    // 10 kHz printed to 0.1 ms from a large offset: exact enough.
    let mut text = String::from("t,v_in,u\n");
    for i in 0..1000 {
        text.push_str(&format!("{:.4},0,0\n", 1000.0 + i as f64 * 1e-4));
    }
    let r = parse_record(&text, p(), RecordKind::Measured).unwrap();
    assert!((r.sample_rate_hz() - 10_000.0).abs() < 1e-3);
}

#[test]
fn sample_rate_limits() {
    let make = |rate: f64| {
        let mut s = String::from("t,v_in,u,x\n");
        for i in 0..5 {
            s.push_str(&format!("{},0,0,0\n", i as f64 / rate));
        }
        s
    };
    let e = err(&make(100.0), RecordKind::Measured);
    assert!(matches!(e, DatasetError::SampleRate { .. }));
    assert_eq!(
        e.to_string(),
        "ride.csv: sample rate 100 Hz (step 0.01 s) is outside 200 ..= 10000 Hz allowed for \
         a measured record"
    );
    assert!(parse_record(&make(100.0), p(), RecordKind::Excitation).is_ok());
    assert!(parse_record(&make(200.0), p(), RecordKind::Measured).is_ok());
    assert!(parse_record(&make(10_000.0), p(), RecordKind::Measured).is_ok());
    assert!(parse_record(&make(10.0), p(), RecordKind::Excitation).is_ok());
    assert!(parse_record(&make(100_000.0), p(), RecordKind::Excitation).is_ok());
    let e = err(&make(20_000.0), RecordKind::Measured);
    assert!(
        e.to_string()
            .contains("sample rate 20000 Hz (step 0.00005 s)"),
        "{e}"
    );
    let e = err(&make(5.0), RecordKind::Excitation);
    assert!(
        e.to_string()
            .ends_with("outside 10 ..= 100000 Hz allowed for an excitation record"),
        "{e}"
    );
    assert!(matches!(
        err(&make(200_000.0), RecordKind::Excitation),
        DatasetError::SampleRate { .. }
    ));
}

#[test]
fn metadata_rate_mismatch_is_a_warning() {
    let text = "# sample_rate_hz: 500\nt,v_in,u\n0,0,0\n0.001,0,0\n0.002,0,0\n";
    let r = parse_record(text, p(), RecordKind::Measured).unwrap();
    assert_eq!(r.warnings.len(), 1);
    assert!(
        r.warnings[0].contains("sample_rate_hz: \"500\" disagrees"),
        "{:?}",
        r.warnings
    );
}

#[test]
fn encoding_errors() {
    let e = parse_record_bytes(b"t,x\n0,1\n0.1,\xff\n", p(), RecordKind::Excitation).unwrap_err();
    assert!(matches!(e, DatasetError::Encoding { line: 3, .. }), "{e:?}");
    assert_eq!(
        e.to_string(),
        "ride.csv: line 3: not UTF-8 text: invalid byte 0xff at character 5 of the line \
         (byte offset 12 in the file)"
    );
    let e = parse_record_bytes(b"\xff\xfet\x00", p(), RecordKind::Excitation).unwrap_err();
    assert!(e.to_string().contains("UTF-16"), "{e}");
    let e = parse_record_bytes(b"t,x\n0,\x001\n", p(), RecordKind::Excitation).unwrap_err();
    assert_eq!(
        e.to_string(),
        "ride.csv: line 2: not UTF-8 text: a NUL byte (0x00) at character 3 of the line \
         (byte offset 6 in the file): this is not a text file"
    );
    // Through a real file.
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("bad.csv");
    std::fs::write(&f, b"# caf\xe9\nt,x\n").unwrap();
    let e = read_record(&f, RecordKind::Excitation).unwrap_err();
    assert!(e.to_string().contains("bad.csv: line 1: not UTF-8"), "{e}");
}

#[test]
fn too_large_file_is_refused_before_reading() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("huge.csv");
    let file = File::create(&f).unwrap();
    // A sparse file: no disk space used, and never read.
    file.set_len(MAX_FILE_BYTES + 1).unwrap();
    let e = read_record(&f, RecordKind::Measured).unwrap_err();
    assert!(matches!(e, DatasetError::TooLarge { .. }), "{e}");
    assert!(
        e.to_string()
            .ends_with("huge.csv: 536870913 bytes is over the limit of 536870912 bytes (512 MiB)"),
        "{e}"
    );
}

#[test]
fn plausibility_warnings() {
    let text = "t,v_in,u\n0,0,0\n0.001,-12.5,0.02\n0.002,3,-30\n0.003,0,0\n";
    let r = parse_record(text, p(), RecordKind::Measured).unwrap();
    assert_eq!(
        r.warnings,
        vec![
            "column \"u\" reaches -30 m at line 4, far beyond the rig's stroke of ±35 mm: \
             is it in millimetres instead of metres? (the format is SI)"
                .to_string(),
            "column \"v_in\" reaches -12.5 V at line 3, beyond the valve's ±10 V (the twin \
             saturates the command there)"
                .to_string(),
        ]
    );
    let text = "t,v_in,u\n0,10,0.035\n0.001,-10,-0.035\n";
    let r = parse_record(text, p(), RecordKind::Measured).unwrap();
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
}

#[test]
fn devices_and_binary_files_fail_after_a_short_read() {
    let e = read_record(Path::new("/dev/zero"), RecordKind::Measured).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("/dev/zero: line 1: not UTF-8 text: a NUL byte"),
        "{e}"
    );
    let e = read_record(Path::new("/dev/urandom"), RecordKind::Measured).unwrap_err();
    assert!(matches!(e, DatasetError::Encoding { .. }), "{e}");
    let e = read_record(Path::new("/"), RecordKind::Measured).unwrap_err();
    assert_eq!(
        e.to_string(),
        "/: cannot read: is a directory, not a CSV file"
    );
}

#[test]
fn too_many_rows() {
    let text = "# a\nt,x\n0,0\n0.1,0\n\n0.2,0\n0.3,0\n";
    assert!(parse_with_row_limit(text, p(), RecordKind::Excitation, 4).is_ok());
    let e = parse_with_row_limit(text, p(), RecordKind::Excitation, 3).unwrap_err();
    assert!(matches!(e, DatasetError::TooManyRows { .. }), "{e}");
    assert_eq!(e.to_string(), "ride.csv: line 7: more than 3 data rows");
}

#[test]
fn line_map() {
    let mut m = LineMap { jumps: Vec::new() };
    for (row, line) in [(0, 5), (1, 6), (2, 8), (3, 9), (4, 12)] {
        m.push(row, line);
    }
    assert_eq!(m.jumps, vec![(0, 5), (2, 8), (4, 12)]);
    let lines: Vec<usize> = (0..5).map(|r| m.line_of(r)).collect();
    assert_eq!(lines, vec![5, 6, 8, 9, 12]);
}

#[test]
fn number_formats() {
    for x in [
        0.0,
        -0.0,
        1.0,
        0.1,
        1e-5,
        9.99e-6,
        1e15,
        123456.789,
        -2.5e-300,
        f64::MAX,
        f64::MIN_POSITIVE,
        5e-324,
    ] {
        let s = fmt_num(x);
        assert_eq!(
            s.parse::<f64>().unwrap().to_bits(),
            x.to_bits(),
            "{x} -> {s}"
        );
        assert!(s.len() < 30, "{s}");
    }
    assert_eq!(sig(0.0015000000000000013), "0.0015");
    assert_eq!(sig(20_000.000000001), "20000");
}

#[test]
fn round_trip_through_write_csv_atomic() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("out.csv");
    let header = ["t", "v_in", "u", "x", "xdd", "ydd", "p1", "p2"];
    let comments = vec![
        ("experiment".to_string(), "round trip: a, b".to_string()),
        ("sample_rate_hz".to_string(), "2000".to_string()),
    ];
    let rows: Vec<Vec<f64>> = (0..500)
        .map(|i| {
            let t = i as f64 / 2000.0;
            vec![
                t,
                (t * 7.0).sin(),
                1e-7 * i as f64,
                -3.3e-20,
                1.0 / 3.0,
                1e6,
                2.0e5 + t,
                -0.0,
            ]
        })
        .collect();
    write_csv_atomic(&f, &header, &comments, rows.clone().into_iter()).unwrap();
    let r = read_record(&f, RecordKind::Measured).unwrap();
    assert_eq!(r.metadata, comments);
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    assert_eq!(r.len(), 500);
    for (j, name) in header.iter().enumerate() {
        let col = r.column(name).unwrap();
        for (i, row) in rows.iter().enumerate() {
            assert_eq!(col[i].to_bits(), row[j].to_bits(), "{name}[{i}]");
        }
    }
    // Only the target file is left in the directory.
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("out.csv")]);
}

#[test]
fn write_refuses_what_would_not_read_back_and_leaves_the_old_file() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("keep.csv");
    std::fs::write(&f, "old").unwrap();
    let ok_rows = || vec![vec![0.0, 1.0]].into_iter();
    type Case = (Vec<&'static str>, Vec<(String, String)>, Vec<Vec<f64>>);
    let bad: Vec<Case> = vec![
        (vec![], vec![], vec![]),
        (vec!["t", "t"], vec![], vec![]),
        (vec!["t", "a,b"], vec![], vec![]),
        (vec!["t", "#x"], vec![], vec![]),
        (vec!["t", ""], vec![], vec![]),
        (vec!["t", "x"], vec![("a:b".into(), "c".into())], vec![]),
        (vec!["t", "x"], vec![("a".into(), "c\nd".into())], vec![]),
        (vec!["t", "x"], vec![], vec![vec![0.0, 1.0], vec![0.1]]),
        (
            vec!["t", "x"],
            vec![],
            vec![vec![0.0, 1.0], vec![0.1, f64::NAN]],
        ),
        (
            vec!["t", "x"],
            vec![],
            vec![vec![0.0, 1.0], vec![0.1, 1e300]],
        ),
    ];
    for (h, c, rows) in bad {
        let e = write_csv_atomic(&f, &h, &c, rows.into_iter()).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput, "{e}");
        assert_eq!(std::fs::read_to_string(&f).unwrap(), "old");
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    write_csv_atomic(&f, &["t", "x"], &[], ok_rows()).unwrap();
    assert_eq!(std::fs::read_to_string(&f).unwrap(), "t,x\n0,1\n");
    // A missing directory is an error, not a panic.
    assert!(write_csv_atomic(Path::new("/nonexistent-dir/x.csv"), &["t"], &[], ok_rows()).is_err());
}

#[test]
fn demo_campaign_files_parse() {
    let dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo-campaign"));
    if !dir.is_dir() {
        println!(
            "note: {} not found; demo-campaign check skipped",
            dir.display()
        );
        return;
    }
    let expected = [
        ("bump.csv", 6001),
        ("ride.csv", 30001),
        ("sine_01hz_0.72v.csv", 6001),
        ("sine_02hz_2.10v.csv", 3001),
        ("sine_05hz_0.72v.csv", 3001),
        ("sine_05hz_4.50v.csv", 3001),
        ("sine_10hz_1.10v.csv", 3001),
        ("sine_10hz_6.40v.csv", 3001),
        ("sine_15hz_3.00v.csv", 3001),
        ("sine_20hz_0.72v.csv", 3001),
    ];
    for (name, rows) in expected {
        let f = dir.join(name);
        let r = read_record(&f, RecordKind::Measured).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(r.len(), rows, "{name}");
        assert!(
            (r.sample_rate_hz() - 1000.0).abs() < 1e-6,
            "{name}: {}",
            r.sample_rate_hz()
        );
        assert!(r.warnings.is_empty(), "{name}: {:?}", r.warnings);
        assert_eq!(r.metadata_value("sample_rate_hz"), Some("1000"));
        for c in ["v_in", "u", "x", "xdd", "ydd"] {
            assert_eq!(r.column(c).map(<[f64]>::len), Some(rows), "{name} {c}");
        }
        assert!(r.p1.is_none() && r.p2.is_none());
        let dur: f64 = r.metadata_value("duration_s").unwrap().parse().unwrap();
        assert!((r.duration_s() - dur).abs() < 1e-9, "{name}");
        let x = read_record(&f, RecordKind::Excitation).unwrap_or_else(|e| panic!("{e}"));
        assert!(x.warnings.is_empty(), "{name}: {:?}", x.warnings);
    }
}

#[test]
fn parses_a_long_seven_column_record() {
    // 6 s at 10 kHz, every column present. (How fast this parses is a matter for a benchmark,
    // not for a test: no time is measured here.)
    let rate = 10_000.0;
    let n = 60_000;
    let row = |i: usize| {
        let t = i as f64 / rate;
        let s = (t * 31.4).sin();
        format!(
            "{:.4},{:.6},{:.6e},{:.6e},{:.6},{:.6},{:.1}",
            t,
            0.72 * s,
            1e-3 * s,
            2e-5 * s,
            0.3 * s,
            1.1 * s,
            2.0e6 + 1e5 * s
        )
    };
    let mut text = String::with_capacity(n * 90);
    text.push_str("# sample_rate_hz: 10000\nt,v_in,u,x,xdd,ydd,p1\n");
    for i in 0..n {
        let _ = writeln!(text, "{}", row(i));
    }
    let r = parse_record(&text, p(), RecordKind::Measured).unwrap();
    assert_eq!(r.len(), n);
    assert!((r.duration_s() - (n - 1) as f64 / rate).abs() < 1e-6);
    assert!((r.dt - 1.0 / rate).abs() < 1e-12);
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    // Every column of a row far into the file holds the numbers written there.
    for i in [0, 12_345, n - 1] {
        let cells: Vec<f64> = row(i).split(',').map(|c| c.parse().unwrap()).collect();
        for (k, name) in ["t", "v_in", "u", "x", "xdd", "ydd", "p1"]
            .iter()
            .enumerate()
        {
            assert_eq!(r.column(name).unwrap()[i], cells[k], "row {i}, {name}");
        }
    }
    assert!(r.p2.is_none());
}

/// The message [`parse_record_bytes`] gives for the first bad byte of `b`, found on the whole
/// file at once (the reference for the chunked check).
fn whole_file_text_error(b: &[u8]) -> Option<String> {
    let invalid = std::str::from_utf8(b).err().map(|e| e.valid_up_to());
    let nul = b.iter().position(|&x| x == 0);
    let (at, is_nul) = match (invalid, nul) {
        (Some(i), Some(n)) if n < i => (n, true),
        (Some(i), _) => (i, false),
        (None, Some(n)) => (n, true),
        (None, None) => return None,
    };
    let (line, col) = crate::fsutil::line_column(b, at);
    let head = format!("ride.csv: line {line}: not UTF-8 text:");
    let place = format!("at character {col} of the line (byte offset {at} in the file)");
    Some(if is_nul {
        format!("{head} a NUL byte (0x00) {place}: this is not a text file")
    } else {
        format!("{head} invalid byte 0x{:02x} {place}", b[at])
    })
}

/// The text check reads a file in 64 KiB chunks: a bad byte, a NUL, a lone CR or a character
/// cut by a chunk's end names the same line, character and byte offset as a check of the
/// whole file would, and a CR LF pair split by a chunk's end is a line end.
#[test]
fn text_errors_across_chunk_ends_name_the_whole_file_position() {
    const CHUNK: usize = 64 * 1024;
    // Comment rows of "é" (2 bytes) so that characters straddle chunk ends at every phase.
    let mut body = String::from("t,x\n");
    let mut i = 0;
    while body.len() < 2 * CHUNK + 100 {
        let _ = writeln!(body, "# é{}", "é".repeat(i % 7));
        i += 1;
    }
    let base = body.into_bytes();
    let mut checked = 0;
    for at in (CHUNK - 5..CHUNK + 5).chain(2 * CHUNK - 4..2 * CHUNK + 4) {
        // A byte that is never valid, a NUL, a lead byte without its continuation and a stray
        // continuation byte.
        for bad in [0xffu8, 0x00, 0xc3, 0xa9] {
            let mut b = base.clone();
            b[at] = bad;
            let Some(expected) = whole_file_text_error(&b) else {
                continue;
            };
            let e = parse_record_bytes(&b, p(), RecordKind::Excitation).unwrap_err();
            assert_eq!(e.to_string(), expected, "byte {bad:#04x} at {at}");
            checked += 1;
        }
        // A CR at `at`: lone unless a LF follows (then the file is text, with no data rows).
        let mut b = base.clone();
        if b[at] < 0x80 && b[at + 1] < 0x80 && b[at] != b'\n' {
            b[at] = b'\r';
            let e = parse_record_bytes(&b, p(), RecordKind::Excitation).unwrap_err();
            if b[at + 1] == b'\n' {
                assert!(matches!(e, DatasetError::Empty { .. }), "{at}: {e}");
            } else {
                let line = crate::fsutil::line_column(&b, at).0;
                assert!(
                    matches!(e, DatasetError::LoneCarriageReturn { line: l, .. } if l == line),
                    "{at}: {e}"
                );
            }
        }
    }
    assert!(checked > 60, "{checked}");
    // Through a real file (read in chunks by the file reader, not from a slice).
    let mut b = base.clone();
    b[CHUNK + 1] = 0xff;
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("ride.csv");
    std::fs::write(&f, &b).unwrap();
    let e = read_record(&f, RecordKind::Excitation).unwrap_err();
    let expected = whole_file_text_error(&b).unwrap();
    let expected = expected.replacen("ride.csv", &f.display().to_string(), 1);
    assert_eq!(e.to_string(), expected);
    // CR LF pairs at every phase of the chunk end: a valid record.
    for shift in 0..4 {
        let mut text = "#".repeat(CHUNK - 2 - shift);
        text.push_str("\r\nt,x\r\n");
        for k in 0..4 {
            let _ = write!(text, "{k}e-2,0\r\n");
        }
        let r = parse_record(&text, p(), RecordKind::Excitation).unwrap();
        assert_eq!(r.len(), 4);
        assert_eq!(r.t, [0.0, 0.01, 0.02, 0.03]);
    }
}

/// Every k-th sample from the first, every column alike, the step k times longer; k = 1
/// gives the record itself.
#[test]
fn a_decimated_record_keeps_every_kth_sample_of_every_column() {
    let n = 11;
    let col = |a: f64| Some((0..n).map(|i| a * i as f64).collect::<Vec<f64>>());
    let r = Record {
        path: "fast.csv".into(),
        metadata: vec![("sample_rate_hz".into(), "10000".into())],
        dt: 1e-4,
        t: (0..n).map(|i| i as f64 * 1e-4).collect(),
        v_in: col(1.0),
        u: col(2.0),
        x: None,
        xdd: col(3.0),
        ydd: col(4.0),
        p1: col(5.0),
        p2: None,
        warnings: vec![],
    };
    let d = r.decimated(5);
    assert_eq!(d.len(), 3);
    assert!((d.dt - 5e-4).abs() < 1e-18);
    assert_eq!(d.t, vec![0.0, 5e-4, 1e-3]);
    assert_eq!(d.u, Some(vec![0.0, 10.0, 20.0]));
    assert_eq!(d.p1, Some(vec![0.0, 25.0, 50.0]));
    assert_eq!((d.x, d.p2), (None, None));
    assert_eq!(d.metadata, r.metadata);
    let same = r.decimated(1);
    assert_eq!(
        (same.t, same.ydd, same.dt),
        (r.t.clone(), r.ydd.clone(), r.dt)
    );
}
