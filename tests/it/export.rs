//! `seat-twin export`: the FMU archive from the CLI, and the C controller compiled with gcc and
//! fed the sensor samples of a closed-loop run with saturation, against the Rust controller
//! it mirrors (double variant bit for bit, float variant within a stated bound). The FMU's
//! behaviour under an independent importer is checked by FMPy (`.ci/checks/fmu.sh`).

use crate::support::bin;
use seat_twin::export::controller::{self, SampledController};
use seat_twin::params::{ControllerKind, Params};
use seat_twin::preset::Preset;
use seat_twin::scenario::{Cycloid, PlatformMotion};
use seat_twin::simulation::{Drive, Run, Simulation};
use std::path::Path;
use std::process::Command;

/// Controller rate of the tests [Hz].
const RATE_HZ: f64 = 1000.0;

/// Largest difference of the float variant's command from the double one's [V] on the
/// closed-loop run below. Measured (gcc 12, x86-64): 0.99 µV paper, 1.9 µV predictive,
/// 3.2 µV skyhook, 0.93 µV smith, of commands up to the ±10 V saturation: single precision's
/// 6e-8 rounding, accumulated by ∫ẍ and the filters over 1500 steps.
const FLOAT_BOUND_V: f64 = 2e-5;

/// The sensor samples `(u, ẍ, ÿ)` of the paper's closed loop on the twin over a violent
/// bump (100 mm in 0.12 s, platform velocity up to 1.7 m/s: the paper's law asks for more
/// than ±10 V), at [`RATE_HZ`].
fn closed_loop_sensors() -> Vec<[f64; 3]> {
    let p = Params::paper();
    let bump = Cycloid {
        height_m: 0.1,
        rise_time_s: 0.12,
        start_s: 0.1,
    };
    let mut sim = Simulation::twin(
        &p,
        p.numerics.max_step_s,
        Drive::closed_loop(&p),
        PlatformMotion::Cycloid(bump),
    );
    let trace = sim.run_trace(1.5, RATE_HZ).expect("the bump run completes");
    trace.samples.iter().map(|s| [s.u, s.xdd, s.ydd]).collect()
}

/// Compiles the exported controller with a driver that reads `(u, ẍ, ÿ)` triples as
/// doubles on stdin and writes each variant's command as a double on stdout.
fn compile(dir: &Path) -> std::path::PathBuf {
    let driver = r#"
#include <stdio.h>
#include "seat_controller.h"
int main(void)
{
    seat_ctrl_state s;
    seat_ctrl_state_f sf;
    double in[3];
    seat_ctrl_init(&s);
    seat_ctrl_init_f(&sf);
    while (fread(in, sizeof in[0], 3, stdin) == 3) {
        double out[2];
        out[0] = seat_ctrl_step(&s, in[0], in[1], in[2]);
        out[1] = (double)seat_ctrl_step_f(&sf, (float)in[0], (float)in[1], (float)in[2]);
        if (fwrite(out, sizeof out[0], 2, stdout) != 2) {
            return 1;
        }
    }
    return 0;
}
"#;
    std::fs::write(dir.join("driver.c"), driver).unwrap();
    let exe = dir.join("driver");
    let out = Command::new("gcc")
        .args([
            "-std=c99",
            "-Wall",
            "-Wextra",
            "-Werror",
            "-ffp-contract=off",
            "-O2",
            "-o",
        ])
        .arg(&exe)
        .arg(dir.join("driver.c"))
        .arg(dir.join("seat_controller.c"))
        .current_dir(dir)
        .output()
        .expect("gcc runs");
    assert!(
        out.status.success(),
        "gcc refused the exported code:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    exe
}

fn run_driver(exe: &Path, sensors: &[[f64; 3]]) -> Vec<[f64; 2]> {
    use std::io::Write;
    let mut child = Command::new(exe)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let bytes: Vec<u8> = sensors
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    child.stdin.take().unwrap().write_all(&bytes).unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    out.stdout
        .chunks_exact(16)
        .map(|c| {
            [
                f64::from_le_bytes(c[..8].try_into().unwrap()),
                f64::from_le_bytes(c[8..].try_into().unwrap()),
            ]
        })
        .collect()
}

#[test]
fn c_controller_equals_the_rust_controller_bit_for_bit_for_every_kind() {
    let sensors = closed_loop_sensors();
    for kind in ControllerKind::ALL {
        let mut params = Params::paper();
        params.controller.kind = kind;
        let preset = Preset {
            params,
            ..Preset::paper()
        };
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("ctl");
        controller::write(&preset, "paper", RATE_HZ, &out, &mut |_, _| {}).unwrap();
        let exe = compile(&out);
        let c = run_driver(&exe, &sensors);
        assert_eq!(c.len(), sensors.len());
        let mut rust = SampledController::new(&params, RATE_HZ);
        let v_max = params.plant.valve.v_max_v;
        let (mut saturated, mut float_err) = (0, 0.0f64);
        for (n, (s, got)) in sensors.iter().zip(&c).enumerate() {
            let want = rust.step(s[0], s[1], s[2]);
            assert_eq!(
                got[0].to_bits(),
                want.to_bits(),
                "{kind}: sample {n}: C {} vs Rust {want}",
                got[0]
            );
            saturated += usize::from(want.abs() == v_max);
            float_err = float_err.max((got[1] - want).abs());
        }
        eprintln!(
            "{kind}: {} samples, {saturated} saturated, float variant within {float_err:.2e} V",
            sensors.len()
        );
        assert!(
            saturated > 20,
            "{kind}: the run saturates ({saturated} samples)"
        );
        assert!(
            float_err <= FLOAT_BOUND_V,
            "{kind}: float variant off by {float_err} V"
        );
    }
}

/// The FMU's slave, driven at 1 ms communication steps with a record's value and forward
/// slope at each point, against the twin run by `simulate`'s stepper on the same record (a
/// platform acceleration linear between knots 10 ms apart, sampled at 0.25 ms): equal to
/// round-off. (FMPy repeats this through the C API at 0.5, 1 and 10 ms in `.ci/checks`.)
#[test]
fn fmu_slave_equals_the_simulation_on_a_record_linear_between_communication_points() {
    use seat_twin::export::fmi2::slave::Slave;
    use seat_twin::export::fmu::{ControllerPlacement, OUTPUTS, VR_OUTPUTS, VR_XDD};
    use seat_twin::scenario::SampledMotion;
    let p = Params::paper();
    let (knot, fine, comm) = (0.01, 0.25e-3, 1e-3);
    let knots: Vec<f64> = (0..=100)
        .map(|j| {
            let t = j as f64 * knot;
            if t <= 0.02 {
                0.0
            } else {
                0.8 * (2.0 * std::f64::consts::PI * 3.1 * t).sin()
                    + 0.4 * (2.0 * std::f64::consts::PI * 7.3 * t).cos()
            }
        })
        .collect();
    let per = 40;
    let value = |i: usize| {
        let j = (i / per).min(knots.len() - 2);
        let m = i - j * per;
        knots[j] + (knots[j + 1] - knots[j]) * (m as f64 / per as f64)
    };
    let record: Vec<f64> = (0..=(knots.len() - 1) * per).map(value).collect();
    let mut sim = Simulation::twin(
        &p,
        p.numerics.max_step_s,
        Drive::closed_loop(&p),
        PlatformMotion::Sampled(SampledMotion::from_acceleration(fine, record)),
    );
    let trace = sim.run_trace(0.99, 1.0 / comm).unwrap();

    let mut slave = Slave::new(p, ControllerPlacement::Internal);
    slave.setup(0.0).unwrap();
    slave.enter_initialization().unwrap();
    slave.exit_initialization().unwrap();
    let channels =
        |x: &seat_twin::simulation::Sample| [x.u, x.ydd, x.p1, x.p2, x.q1, x.q2, x.xv, x.v_in];
    // Each output's excursion from rest over the run.
    let rest = channels(&trace.samples[0]);
    let mut scale = [0.0f64; 8];
    for x in &trace.samples {
        for (o, v) in channels(x).iter().enumerate() {
            scale[o] = scale[o].max((v - rest[o]).abs());
        }
    }
    let mut worst = 0.0f64;
    for (k, s) in trace.samples.iter().enumerate().skip(1) {
        let i = (k - 1) * 4;
        let slope = (knots[i / per + 1] - knots[i / per]) / knot;
        slave.set(VR_XDD, value(i)).unwrap();
        slave.set_derivative(VR_XDD, 1, slope).unwrap();
        slave.do_step((k - 1) as f64 * comm, comm).unwrap();
        for (o, want) in channels(s).iter().enumerate() {
            let got = slave.get(VR_OUTPUTS + o as u32).unwrap();
            let err = (got - want).abs() / scale[o];
            assert!(
                err <= 1e-9,
                "{} at t = {}: {got} vs {want}",
                OUTPUTS[o].0,
                s.t
            );
            worst = worst.max(err);
        }
    }
    eprintln!("FMU slave vs simulation: largest error {worst:.1e} of the excursion");
}

#[test]
fn export_fmu_writes_an_archive_and_refuses_bad_options() {
    let dir = tempfile::tempdir().unwrap();
    let fmu = dir.path().join("seat_twin.fmu");
    // `cargo test` builds no cdylib (`cargo build` does), so the packing is checked with a
    // stand-in library given by `--library`; the real one is loaded and run by FMPy in
    // .ci/checks/fmu.sh, and the app's test checks the refusal when it is missing.
    let library = dir.path().join("libseat_twin.so");
    std::fs::write(&library, b"\x7fELF stand-in for the packing test").unwrap();
    let out = bin()
        .args(["export", "fmu", "--library"])
        .arg(&library)
        .arg("--out")
        .arg(&fmu)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let zip = std::fs::read(&fmu).unwrap();
    let has = |name: &str| zip.windows(name.len()).any(|w| w == name.as_bytes());
    for entry in [
        "modelDescription.xml",
        "binaries/linux64/seat_twin.so",
        "resources/preset.toml",
        "resources/controller",
    ] {
        assert!(has(entry), "the FMU holds {entry}");
    }
    // The library missing: a clear error, nothing written.
    let other = dir.path().join("other.fmu");
    let out = bin()
        .args([
            "export",
            "fmu",
            "--library",
            "/nonexistent/libseat_twin.so",
            "--out",
        ])
        .arg(&other)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1));
    assert!(err.contains("cargo build --release"), "{err}");
    assert!(!other.exists());
    // Not an .fmu name; a rate out of range.
    let out = bin()
        .args(["export", "fmu", "--out", "x.zip"])
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&out.stderr).contains(".fmu"));
    let out = bin()
        .args([
            "export",
            "controller",
            "--rate",
            "10",
            "--lang",
            "c",
            "--out",
        ])
        .arg(dir.path().join("c"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--rate 10 is outside the allowed range [50, 100000] Hz"),
        "{err}"
    );
    assert!(!dir.path().join("c").exists());
}
