"""Checks the exported controller's discretisation against python-control.

Usage: python check_controller.py SEAT_TWIN_EXECUTABLE WORK_DIR

For each controller kind (a preset per kind, written here from the paper's) and two rates,
`seat-twin export controller` writes seat_controller.json: each section's continuous transfer
function, its discretisation method and the discrete coefficients the controller (Rust and C)
uses. `control.sample_system` discretises the continuous form independently; the discrete
frequency responses must agree to 1e-9 (relative) from 0.1 Hz to 0.45 of the rate, and the
Smith model's zero-order-hold matrices element by element.
"""

import json
import os
import subprocess
import sys

import numpy as np
from check_report import check, finish
import control

TOLERANCE = 1e-9
def preset_for(kind, work):
    path = os.path.join(work, f"preset_{kind}.toml")
    with open(path, "w") as f:
        f.write(f'[preset]\nname = "paper-{kind}"\n\n[controller]\nkind = "{kind}"\n')
    return path


def response(num, den, z):
    return np.polyval(num, z) / np.polyval(den, z)


def main():
    exe, work = sys.argv[1], sys.argv[2]
    os.makedirs(work, exist_ok=True)
    for kind in ("paper", "predictive", "skyhook", "smith"):
        for rate in (250.0, 1000.0):
            out = os.path.join(work, f"controller_{kind}_{rate:g}")
            subprocess.run([exe, "export", "controller", "--preset", preset_for(kind, work),
                            "--rate", repr(rate), "--lang", "c", "--out", out], check=True,
                           stdout=subprocess.DEVNULL)
            with open(os.path.join(out, "seat_controller.json")) as f:
                spec = json.load(f)
            h = spec["step_s"]
            check(abs(h - 1.0 / rate) < 1e-15, f"{kind} {rate:g} Hz: step {h}")
            freqs = np.geomspace(0.1, 0.45 * rate, 25)
            z = np.exp(2j * np.pi * freqs * h)
            for sec in spec["sections"]:
                c = sec["continuous"]
                ref = control.sample_system(control.tf(c["num"], c["den"]), h, method=sec["method"])
                num = np.atleast_1d(np.squeeze(ref.num[0][0]))
                den = np.atleast_1d(np.squeeze(ref.den[0][0]))
                want = response(num, den, z)
                got = response(sec["discrete"]["num"], sec["discrete"]["den"], z)
                err = np.max(np.abs(got - want) / np.abs(want))
                check(err <= TOLERANCE,
                      f"{kind} {rate:g} Hz: {sec['name']} ({sec['method']}) = sample_system, "
                      f"largest relative error {err:.1e}")
            smith = spec["smith_model"]
            if smith is not None:
                a = np.array(smith["continuous"]["A"])
                b = np.array(smith["continuous"]["B"]).reshape(3, 1)
                ref = control.sample_system(control.ss(a, b, np.eye(3), np.zeros((3, 1))), h,
                                            method="zoh")
                for name, got, want in (("A", np.array(smith["discrete"]["A"]), ref.A),
                                        ("B", np.array(smith["discrete"]["B"]).reshape(3, 1), ref.B)):
                    err = np.max(np.abs(got - want)) / np.max(np.abs(want))
                    check(err <= TOLERANCE,
                          f"{kind} {rate:g} Hz: Smith model {name} (zoh) = sample_system, "
                          f"largest error {err:.1e} of its largest element")
    finish("controller")


if __name__ == "__main__":
    main()
