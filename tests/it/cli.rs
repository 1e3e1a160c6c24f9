//! The headless CLI on real files: the stable interface of issue 2 (column names, units,
//! errors that name the file/line/column, exit codes, no partial output files).

use crate::support::{bin, cli, column, read_csv, stderr, tmp};
use std::path::PathBuf;

#[test]
fn simulate_twin_cycloid_writes_the_documented_columns() {
    let dir = tmp();
    let out = dir.path().join("c.csv");
    let o = cli(
        "simulate --model twin --scenario cycloid --duration 2 --out {}",
        &[&out],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let (header, rows) = read_csv(&out);
    assert_eq!(
        header,
        [
            "t", "x", "xdd", "u", "ydd", "v_in", "xv", "p1", "p2", "q1", "q2"
        ]
    );
    assert_eq!(rows.len(), 2001, "1 kHz for 2 s, both ends");
    // The platform ends 30 mm up (SI metres), the body acceleration stays below the platform's.
    let x = column(&header, &rows, "x");
    assert!((x.last().unwrap() - 0.030).abs() < 1e-9);
    let peak = |v: &[f64]| v.iter().fold(0.0f64, |m, a| m.max(a.abs()));
    let ydd = column(&header, &rows, "ydd");
    let xdd = column(&header, &rows, "xdd");
    assert!(peak(&ydd) < 0.5 * peak(&xdd));
    // Pressures are in Pa: the rest pressure is (pA + p0)/2 = 55 bar.
    let p1 = column(&header, &rows, "p1");
    assert!((p1[0] - 55e5).abs() < 1.0);
}

/// The stepping loop compiled for AVX (used when the processor has it) and the baseline SSE2
/// form give the same trace bit for bit, for every model: the wider form only changes how
/// many lanes each product runs in, not the operations or their order.
#[test]
fn the_avx_and_the_portable_stepping_loops_write_the_same_bytes() {
    let dir = tmp();
    for model in ["twin", "linear", "passive"] {
        let mut written = Vec::new();
        for portable in [false, true] {
            let out = dir.path().join(format!("{model}-{portable}.csv"));
            let mut cmd = bin();
            cmd.args(["simulate", "--model", model, "--scenario", "random"])
                .args(["--duration", "3", "--out"])
                .arg(&out);
            if portable {
                cmd.env("SEAT_TWIN_PORTABLE_SIMD", "1");
            } else {
                cmd.env_remove("SEAT_TWIN_PORTABLE_SIMD");
            }
            let o = cmd.output().expect("the binary runs");
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            written.push(std::fs::read(&out).expect("the trace exists"));
        }
        assert!(written[0].len() > 100_000, "{model}: a 3 s trace");
        assert!(written[0] == written[1], "{model}: the two loops differ");
    }
}

#[test]
fn simulate_passive_leaves_out_the_columns_it_lacks() {
    let dir = tmp();
    let out = dir.path().join("p.csv");
    let o = cli(
        "simulate --model passive --scenario random --duration 3 --seed 4 --rate 200 --out {}",
        &[&out],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let (header, rows) = read_csv(&out);
    assert_eq!(header, ["t", "x", "xdd", "u", "ydd"]);
    assert_eq!(rows.len(), 601);
}

#[test]
fn simulate_with_an_excitation_file_runs_the_controller_on_it() {
    let dir = tmp();
    let exc = dir.path().join("base.csv");
    // 2 s of a 1 Hz platform sine of 0.5 m/s² amplitude, starting from rest (sin² ramp-free:
    // acceleration a·sin(ωt) integrates to a velocity that starts at 0).
    let mut text = String::from("# recorded: by hand\nt,xdd\n");
    for n in 0..=2000 {
        let t = n as f64 * 1e-3;
        text.push_str(&format!(
            "{t:.3},{}\n",
            0.5 * (2.0 * std::f64::consts::PI * t).sin()
        ));
    }
    std::fs::write(&exc, text).unwrap();
    let out = dir.path().join("r.csv");
    let o = cli(
        "simulate --model linear --excitation {} --out {}",
        &[&exc, &out],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let (header, rows) = read_csv(&out);
    let xdd = column(&header, &rows, "xdd");
    let v_in = column(&header, &rows, "v_in");
    assert!(
        (xdd[250] - 0.5).abs() < 1e-3,
        "the record drives the platform"
    );
    assert!(
        v_in.iter().any(|v| v.abs() > 1e-3),
        "the controller acts on the record"
    );
}

#[test]
fn a_bad_excitation_file_names_file_line_and_column_and_writes_nothing() {
    let dir = tmp();
    let exc = dir.path().join("bad.csv");
    std::fs::write(&exc, "t,xdd\n0,0\n0.001,0.1\n0.002,abc\n").unwrap();
    let out = dir.path().join("never.csv");
    let o = cli(
        "simulate --model twin --excitation {} --out {}",
        &[&exc, &out],
    );
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("bad.csv"), "{err}");
    assert!(err.contains("line 4"), "{err}");
    assert!(err.contains("xdd"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(!out.exists(), "no partial output");
}

#[test]
fn bode_of_g_at_low_frequency_is_the_paper_gain() {
    let dir = tmp();
    let out = dir.path().join("b.csv");
    let o = cli("bode --model linear --freqs 0.1,1,10 --out {}", &[&out]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (header, rows) = read_csv(&out);
    assert_eq!(header, ["freq_hz", "mag_mm_per_s_v", "phase_deg"]);
    // Kg = 133.25 mm/(s·V); the delay alone gives −360·f·τ degrees at low frequency.
    assert!((rows[0][1] - 133.25).abs() < 0.2, "{:?}", rows[0]);
    assert!(
        (rows[0][2] + 360.0 * 0.1 * 0.0175).abs() < 0.2,
        "{:?}",
        rows[0]
    );
}

#[test]
fn simulated_twin_bode_is_close_to_g_at_1_hz() {
    let dir = tmp();
    let out = dir.path().join("tb.csv");
    let o = cli("bode --model twin --amp 0.72 --freqs 1 --out {}", &[&out]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (_, rows) = read_csv(&out);
    // Section 4: the adjusted twin matches Kg within a few % at low frequency.
    assert!((rows[0][1] / 133.25 - 1.0).abs() < 0.03, "{:?}", rows[0]);
}

#[test]
fn passive_transmissibility_crosses_one_at_sqrt2_fn() {
    let dir = tmp();
    let out = dir.path().join("t.csv");
    // fn = √(k/m)/2π = 2.822 Hz for the paper's 3680 N/m and 11.7 kg.
    let fc = (3680.0f64 / 11.7).sqrt() / (2.0 * std::f64::consts::PI) * 2f64.sqrt();
    let o = cli(
        &format!("transmissibility --model passive --freqs 0.1,{fc} --out {{}}"),
        &[&out],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let (header, rows) = read_csv(&out);
    assert_eq!(header, ["freq_hz", "mag", "phase_deg"]);
    assert!((rows[0][1] - 1.0).abs() < 0.01);
    assert!((rows[1][1] - 1.0).abs() < 1e-6, "{:?}", rows[1]);
}

#[test]
fn a_preset_with_an_out_of_range_value_is_refused_by_name() {
    let dir = tmp();
    let preset = dir.path().join("heavy.toml");
    std::fs::write(&preset, "[body]\nmass_kg = -3.0\n").unwrap();
    let out = dir.path().join("x.csv");
    let o = cli(
        "simulate --model twin --preset {} --scenario cycloid --out {}",
        &[&preset, &out],
    );
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("heavy.toml"), "{err}");
    assert!(err.contains("mass_kg"), "{err}");
    assert!(!out.exists());
}

#[test]
fn a_typo_in_a_preset_is_an_error_with_its_line() {
    let dir = tmp();
    let preset = dir.path().join("typo.toml");
    std::fs::write(&preset, "[valve]\ncd = 0.15\ntau_ss = 0.0175\n").unwrap();
    let out = dir.path().join("t.csv");
    let o = cli(
        "transmissibility --model linear --preset {} --freqs 1 --out {}",
        &[&preset, &out],
    );
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("tau_ss"), "{err}");
    assert!(err.contains("line 3"), "{err}");
}

#[test]
fn an_unknown_model_is_refused() {
    let o = cli(
        "simulate --model quantum --scenario cycloid --out /tmp/never.csv",
        &[],
    );
    assert!(!o.status.success());
    assert!(stderr(&o).contains("quantum"));
}

#[test]
fn report_writes_markdown_numbers_and_plots() {
    let dir = tmp();
    let out: PathBuf = dir.path().join("report");
    let o = cli("report --out {}", &[&out]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in [
        "report.md",
        "numbers.json",
        "table1_bode.png",
        "table1_bode.svg",
        "transmissibility.png",
        "transmissibility.svg",
        "cycloid.png",
        "cycloid.svg",
        "ride.png",
        "ride.svg",
    ] {
        let p = out.join(f);
        assert!(
            p.metadata().map(|m| m.len() > 100).unwrap_or(false),
            "{f} written"
        );
    }
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("| paper"), "the paper-vs-twin table");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("numbers.json")).unwrap()).unwrap();
    let num = |key: &str| {
        json[key]
            .as_f64()
            .unwrap_or_else(|| panic!("numbers.json: `{key}` is a number"))
    };
    // The passive seat crosses |T| = 1 at √2·√(k/m)/2π for the paper's k = 3680 N/m and
    // m = 11.7 kg, whatever its damping.
    let fc = 2f64.sqrt() * (3680.0f64 / 11.7).sqrt() / (2.0 * std::f64::consts::PI);
    let passive = num("passive_crossing_hz");
    assert!(
        (passive / fc - 1.0).abs() < 5e-3,
        "passive crossing {passive} vs {fc}"
    );
    // Section 4: the twin's low-frequency gain u̇/V is Kg = 133.25 mm/(s·V) within a few %.
    let gain = num("twin_gain_m_per_s_v");
    assert!((gain / 0.13325 - 1.0).abs() < 0.03, "twin gain {gain}");
    // G(s)'s phase slope is its delay τ = 17.5 ms plus the lag of its poles: more than τ,
    // and the twin's (the same valve and delay) within a few ms of it.
    let (lin_delay, twin_delay) = (num("linear_phase_delay_s"), num("twin_phase_delay_s"));
    assert!(lin_delay > 0.0175 && lin_delay < 0.05, "{lin_delay}");
    assert!(
        (twin_delay - lin_delay).abs() < 0.005,
        "{twin_delay} vs {lin_delay}"
    );
    // Table 1: the paper's 69 valve tests, each with the twin's |u̇/V| within 30 % of Kg at
    // 0.5–2 Hz (the flat part of G).
    let table = json["table1"].as_array().expect("table1 rows");
    assert_eq!(table.len(), 69);
    for row in table {
        let r: Vec<f64> = row
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        if r[0] <= 2.0 {
            assert!((r[2] / 0.13325 - 1.0).abs() < 0.3, "Table 1 row {r:?}");
        }
    }
    // Eq. (12) solved for Cd: Cd ∝ 1/√Δp between 70 and 100 bar.
    let cd = json["cd_from_eq12"].as_array().unwrap();
    let ratio = cd[0].as_f64().unwrap() / cd[1].as_f64().unwrap();
    assert!((ratio - (100.0f64 / 70.0).sqrt()).abs() < 1e-9, "{ratio}");
}
