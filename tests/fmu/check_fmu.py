"""Checks the seat-twin FMU with FMPy, an independent FMI 2.0 importer.

Usage: python check_fmu.py SEAT_TWIN_EXECUTABLE WORK_DIR

1. fmpy.validate reports no problem for the FMU with the controller inside and outside.
2. Driven by a recorded platform motion, simulate_fmu equals `seat-twin simulate
   --excitation` on the same record to <= 1e-9 (relative to each output's excursion) at
   communication steps of 0.5, 1 and 10 ms.
3. Getting, setting and serialising the FMU state repeats a run bit for bit.
4. With the controller outside, FMPy closes the loop with a Python implementation of the
   paper's law (V = Kp*u + Ki*integral of xdd) and reproduces the internal loop.
5. Bad calls (unknown value reference, value out of range, call in the wrong state) return
   fmi2Error and leave the host running.

The record: a platform acceleration linear between knots 10 ms apart (a rig record at 100 Hz
read with linear interpolation), at rest for its first 20 ms. The FMU gets, at each
communication point, the record's value and its forward slope (fmi2SetRealInputDerivatives,
order 1); `simulate` gets the same piecewise-linear signal sampled at 0.25 ms, half the twin's
step, so that it reads the record's own samples at every grid and mid-step time.
"""

import math
import os
import shutil
import subprocess
import sys

import numpy as np
from check_report import check, finish
import fmpy
from fmpy import read_model_description, extract, instantiate_fmu, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

OUTPUTS = ["u", "ydd", "p1", "p2", "q1", "q2", "xv", "v_in"]
KNOT_S = 0.01
FINE_S = 0.25e-3
DURATION_S = 2.0
TOLERANCE = 1e-9
# Controller outside against inside: the one difference is how the valve reads the delayed
# command between grid points (linear interpolation of the samples received at communication
# points, cubic interpolation of the internal command's history); the integral of xdd is the
# same (trapezoid here, Simpson inside, equal on a record linear between samples).
# Measured: 1.3e-4 of the excursion (ydd) at 0.5 ms.
EXTERNAL_TOLERANCE = 1e-3

def knots():
    """Platform acceleration at the knots [m/s^2]: a few sines 1.9-9 Hz under a fade-in."""
    n = int(round(DURATION_S / KNOT_S)) + 1
    t = np.arange(n) * KNOT_S
    rng = np.random.default_rng(7)
    a = np.zeros(n)
    for f in (1.9, 3.1, 4.7, 6.3, 9.0):
        a += rng.uniform(0.2, 0.5) * np.sin(2 * math.pi * f * t + rng.uniform(0, 2 * math.pi))
    fade = np.clip((t - 0.02) / 0.3, 0.0, 1.0)
    a *= fade * fade * (3 - 2 * fade)
    a[t <= 0.02 + 1e-12] = 0.0
    return [float(v) for v in a]


def record_value(k, t):
    """The record's value at time t (on the fine grid) and its slope to the next knot."""
    j = min(int(math.floor(t / KNOT_S + 1e-9)), len(k) - 2)
    slope = (k[j + 1] - k[j]) / KNOT_S
    i = int(round(t / FINE_S))
    per = int(round(KNOT_S / FINE_S))
    m = i - j * per
    value = k[j] + (k[j + 1] - k[j]) * (m / per)
    return float(value), float(slope)


def write_record(k, path):
    per = int(round(KNOT_S / FINE_S))
    n = (len(k) - 1) * per + 1
    with open(path, "w") as f:
        f.write("# experiment: piecewise-linear platform acceleration, knots every 10 ms\n")
        f.write("t,xdd\n")
        for i in range(n):
            t = i * FINE_S
            v, _ = record_value(k, t)
            f.write(f"{t!r},{v!r}\n")


def read_csv(path):
    with open(path) as f:
        lines = [l for l in f if not l.startswith("#") and l.strip()]
    header = lines[0].strip().split(",")
    data = np.array([[float(c) for c in l.split(",")] for l in lines[1:]])
    return {h: data[:, i] for i, h in enumerate(header)}


def run_fmu(unzipdir, md, k, step, external_law=None):
    """simulate_fmu with the record's value and forward slope set at each communication point
    (and, with `external_law`, the command it computes from the outputs)."""
    fmu = instantiate_fmu(unzipdir, md, "CoSimulation")
    vr = {v.name: v.valueReference for v in md.modelVariables}
    state = {"xd": 0.0, "last": 0.0}

    def set_inputs(time):
        v, slope = record_value(k, time)
        fmu.setReal([vr["xdd"]], [v])
        fmu.setRealInputDerivatives([vr["xdd"]], [1], [slope])
        if external_law is not None:
            state["xd"] += 0.5 * step * (state["last"] + v) if time > 0 else 0.0
            state["last"] = v
            u = fmu.getReal([vr["u"]])[0]
            fmu.setReal([vr["v_in_ext"]], [external_law(u, state["xd"])])

    def step_finished(time, recorder):
        set_inputs(time)
        return True

    # Initialise here so that the inputs at t = 0 (and their slope) are set before the first
    # step; simulate_fmu then only steps and records.
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    set_inputs(0.0)
    result = simulate_fmu(unzipdir, model_description=md, fmu_instance=fmu, initialize=False,
                          terminate=False, stop_time=DURATION_S, output_interval=step,
                          output=OUTPUTS, step_finished=step_finished)
    fmu.terminate()
    fmu.freeInstance()
    return result


def excursion_error(ref, got):
    scale = np.max(np.abs(ref - ref[0]))
    return np.max(np.abs(ref - got)) / scale if scale > 0 else np.max(np.abs(ref - got))


def main():
    exe, work = sys.argv[1], sys.argv[2]
    os.makedirs(work, exist_ok=True)
    fmus = {}
    for placement in ("internal", "external"):
        path = os.path.join(work, f"seat_twin_{placement}.fmu")
        subprocess.run([exe, "export", "fmu", "--controller", placement, "--out", path],
                       check=True)
        problems = validate_fmu(path)
        check(problems == [], f"fmpy.validate of the {placement} FMU: {problems or 'no problems'}")
        unzipdir = os.path.join(work, f"unzipped_{placement}")
        shutil.rmtree(unzipdir, ignore_errors=True)
        extract(path, unzipdir)
        fmus[placement] = (unzipdir, read_model_description(unzipdir))

    k = knots()
    rec = os.path.join(work, "record.csv")
    write_record(k, rec)
    unzipdir, md = fmus["internal"]

    # 2. Against `seat-twin simulate` at three communication steps.
    runs = {}
    for step in (0.5e-3, 1e-3, 10e-3):
        sim_csv = os.path.join(work, f"simulate_{step * 1e3:g}ms.csv")
        subprocess.run([exe, "simulate", "--model", "twin", "--excitation", rec,
                        "--rate", repr(1.0 / step), "--out", sim_csv], check=True,
                       stdout=subprocess.DEVNULL)
        ref = read_csv(sim_csv)
        res = run_fmu(unzipdir, md, k, step)
        runs[step] = res
        n = min(len(ref["t"]), len(res["time"]))
        check(n == int(round(DURATION_S / step)) + 1,
              f"{step * 1e3:g} ms: {n} communication points compared")
        check(np.max(np.abs(ref["t"][:n] - res["time"][:n])) < 1e-9, f"{step * 1e3:g} ms: same times")
        worst = max((excursion_error(ref[c][:n], res[c][:n]), c) for c in OUTPUTS)
        check(worst[0] <= TOLERANCE,
              f"{step * 1e3:g} ms: FMU = simulate, largest error {worst[0]:.2e} of the "
              f"excursion ({worst[1]}), tolerance {TOLERANCE:g}")

    # 3. State: get, set, serialise and deserialise repeat a run bit for bit.
    step = 1e-3
    fmu = instantiate_fmu(unzipdir, md, "CoSimulation")
    vr = {v.name: v.valueReference for v in md.modelVariables}
    out_vrs = [vr[c] for c in OUTPUTS]
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()

    def advance(t0, t1):
        rows = []
        t = t0
        while t < t1 - 1e-12:
            v, slope = record_value(k, t)
            fmu.setReal([vr["xdd"]], [v])
            fmu.setRealInputDerivatives([vr["xdd"]], [1], [slope])
            fmu.doStep(currentCommunicationPoint=t, communicationStepSize=step)
            t = round(t + step, 12)
            rows.append(fmu.getReal(out_vrs))
        return np.array(rows)

    advance(0.0, 0.5)
    saved = fmu.getFMUstate()
    first = advance(0.5, 1.0)
    fmu.setFMUstate(saved)
    again = advance(0.5, 1.0)
    check(np.array_equal(first.view(np.uint64), again.view(np.uint64)),
          "fmi2SetFMUstate repeats the run bit for bit")
    blob = fmu.serializeFMUstate(saved)
    restored = fmu.deSerializeFMUstate(blob)
    fmu.setFMUstate(restored)
    third = advance(0.5, 1.0)
    check(np.array_equal(first.view(np.uint64), third.view(np.uint64)),
          f"a serialised and restored state ({len(blob)} bytes) repeats the run bit for bit")
    fmu.freeFMUstate(saved)
    fmu.freeFMUstate(restored)

    # 5. Bad calls: fmi2Error, and the host keeps running.
    def refused(call, what):
        try:
            call()
            check(False, f"{what} is refused")
        except FMICallException as e:
            check(e.status == 3, f"{what} is refused with fmi2Error")

    refused(lambda: fmu.setReal([4242], [1.0]), "an unknown value reference")
    refused(lambda: fmu.setReal([vr["xdd"]], [float("nan")]), "a NaN input")
    refused(lambda: fmu.setReal([vr["controller.kp_v_per_m"]], [1e7]), "a gain out of range")
    refused(lambda: fmu.setReal([vr["body.mass_kg"]], [20.0]), "a fixed parameter while stepping")
    refused(lambda: fmu.doStep(currentCommunicationPoint=0.25, communicationStepSize=step),
            "a step from the wrong time")
    refused(lambda: fmu.doStep(currentCommunicationPoint=1.0, communicationStepSize=0.3e-3),
            "a step that is not a multiple of the internal step")
    refused(lambda: fmu.enterInitializationMode(), "fmi2EnterInitializationMode while stepping")
    fmu.terminate()
    fmu.freeInstance()

    # 4. The loop closed outside by FMPy with the paper's law, against the internal loop.
    unzip_ext, md_ext = fmus["external"]
    kp = next(float(v.start) for v in md.modelVariables if v.name == "controller.kp_v_per_m")
    ki = next(float(v.start) for v in md.modelVariables if v.name == "controller.ki_v_s_per_m")
    step = 0.5e-3
    sent = []

    def paper_law(u, xd):
        v = kp * u + ki * xd
        sent.append(v)
        return v

    ext = run_fmu(unzip_ext, md_ext, k, step, external_law=paper_law)
    internal = runs[step]
    # simulate_fmu records the outputs before step_finished sets the next command, so the
    # recorded v_in is one step old: compare the commands the law sent instead.
    ext["v_in"][: len(sent)] = np.array(sent)[: len(ext)]
    worst = max((excursion_error(internal[c], ext[c]), c) for c in OUTPUTS)
    check(worst[0] <= EXTERNAL_TOLERANCE,
          f"paper's law closed in FMPy (Kp {kp:g} V/m, Ki {ki:g} V.s/m) = internal loop: "
          f"largest error {worst[0]:.2e} of the excursion ({worst[1]}), tolerance "
          f"{EXTERNAL_TOLERANCE:g}")

    finish("FMU")


if __name__ == "__main__":
    main()
