"""The checks' shared reporting: one line per check, a non-zero exit when any failed."""

import sys

_failures = []


def check(ok, what):
    """Prints `what` as passed or failed and remembers a failure."""
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        _failures.append(what)


def finish(name):
    """Exits non-zero, naming the count, when a check failed."""
    if _failures:
        print(f"{len(_failures)} {name} check(s) failed")
        sys.exit(1)
    print(f"all {name} checks passed")
