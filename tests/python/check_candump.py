#!/usr/bin/env python3
"""Compare a candump log written by the simulated bus with the frames a test expected.

Usage: check_candump.py LOG EXPECTED_JSONL

LOG is read with python-can's ``can.LogReader`` (candump ``-l`` format, ``.log``), so
this checks that the trace is readable by the standard tooling, not only by our code.
EXPECTED_JSONL has one JSON object per line, written by the Rust test
``tests/tests/candump.rs``::

    {"timestamp": 0.000123, "id": 291, "extended": false, "remote": false,
     "dlc": 2, "data": "dead"}

Frames are compared one by one, in order: identifier, is_extended_id, is_remote_frame,
dlc, data and the time stamp to the microsecond. Prints one line per mismatch (at most
20) and a closing ``N passed, M failed`` line; exits 1 on any mismatch or count
difference, 2 on a usage or input error.
"""

import json
import sys
from decimal import Decimal

try:
    import can
except ImportError:  # pragma: no cover - environment problem, not a test result
    print("check_candump: python-can is not installed (pip install python-can)", file=sys.stderr)
    sys.exit(2)


def micros(value) -> int:
    """A time stamp in seconds (float or Decimal) as whole microseconds."""
    return int((Decimal(str(value)) * 1_000_000).to_integral_value())


def describe(fields) -> str:
    ts, ident, ext, rtr, dlc, data = fields
    kind = "remote" if rtr else "data"
    fmt = "%08X" if ext else "%03X"
    return "%d us %s %s dlc %d [%s]" % (ts, fmt % ident, kind, dlc, data)


def from_message(msg) -> tuple:
    return (
        micros(msg.timestamp),
        msg.arbitration_id,
        bool(msg.is_extended_id),
        bool(msg.is_remote_frame),
        int(msg.dlc),
        bytes(msg.data or b"").hex(),
    )


def from_json(obj) -> tuple:
    return (
        micros(obj["timestamp"]),
        int(obj["id"]),
        bool(obj["extended"]),
        bool(obj["remote"]),
        int(obj["dlc"]),
        str(obj["data"]).lower(),
    )


def main(argv) -> int:
    if len(argv) != 3:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    log_path, json_path = argv[1], argv[2]
    try:
        with can.LogReader(log_path) as reader:
            got = [from_message(m) for m in reader if not m.is_error_frame]
        with open(json_path, encoding="utf-8") as f:
            expected = [
                from_json(json.loads(line, parse_float=Decimal))
                for line in f
                if line.strip()
            ]
    except (OSError, ValueError, KeyError) as e:
        print("check_candump: %s" % e, file=sys.stderr)
        return 2

    passed = failed = 0
    shown = 0
    for k, (g, e) in enumerate(zip(got, expected)):
        if g == e:
            passed += 1
            continue
        failed += 1
        if shown < 20:
            shown += 1
            print("frame %d: log %s, expected %s" % (k, describe(g), describe(e)))
    missing = len(expected) - len(got)
    if missing:
        failed += abs(missing)
        which = "missing from the log" if missing > 0 else "extra in the log"
        print("%d frames %s (log %d, expected %d)" % (abs(missing), which, len(got), len(expected)))
    print("%s: %d frames from %s" % ("check_candump", len(got), log_path))
    print("%d passed, %d failed" % (passed, failed))
    return 0 if failed == 0 and passed > 0 else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
