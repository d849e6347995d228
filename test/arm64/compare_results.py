#!/usr/bin/env python3
"""Compares two fact JSON files numerically: the arm64 and the x86-64 fact-solve's fact-result-v1
answers to the same rounds file, or the two fact-simgen's fact-rounds-v1 files.

    compare_results.py A.json B.json [--tolerance 1e-9]

Every number must agree to the tolerance (absolute; yaws compared as angles, so pi and -pi are
equal), numbers inside texts (the reason quotes the gap) likewise, the rest of every text, every
boolean, null and list length exactly; "timing_us" (wall-clock time) is ignored. When both results
say the rotation optimum is not unique (NOT_UNIQUE), only their status, counts and optimal value
are compared (same_optimum): any optimal rounding is then a valid answer. Prints one line: the largest difference in the file and per top-level key (for a result,
"drones" is the poses), or the first disagreement. Exit 0 when equal, 1 when not, 2 on unreadable
input.
"""
import argparse
import json
import math
import re
import sys

# bound_error is a rounding estimate (of the order of ε‖C‖), not a result: same_optimum uses it.
IGNORED_KEYS = {"timing_us", "bound_error"}
# Results whose rotation optimum is not unique (too few rounds for the summed cost, or an SDP
# certified optimal but not unique): every optimal rounding is an equally valid answer, so the
# poses are arbitrary and only the status, the counts and the optimal value are compared.
NOT_UNIQUE = ("certified_not_unique", "rounds to fix every yaw")
COMPARED_WHEN_NOT_UNIQUE = ("format", "mode", "status", "rounds_used")
# A number inside a text (the "reason" quotes the gap, e.g. "gap 6.4455e-13").
NUMBER = re.compile(r"([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)")


class Differ(Exception):
    pass


def angle_difference(a, b):
    d = math.fmod(a - b, 2 * math.pi)
    if d > math.pi:
        d -= 2 * math.pi
    elif d < -math.pi:
        d += 2 * math.pi
    return abs(d)


def walk(a, b, path, tolerance, largest):
    """Raises Differ at the first disagreement; records the largest |a - b| per top-level key."""
    if isinstance(a, str) and isinstance(b, str):
        text_a, text_b = NUMBER.split(a), NUMBER.split(b)
        if len(text_a) != len(text_b) or text_a[0::2] != text_b[0::2]:
            raise Differ(f"{path}: {a!r} vs {b!r}")
        for x, y in zip(text_a[1::2], text_b[1::2]):
            if not abs(float(x) - float(y)) <= tolerance:
                raise Differ(f"{path}: {a!r} vs {b!r} (the numbers {x} and {y})")
        return
    if isinstance(a, bool) or isinstance(b, bool) or a is None or b is None or isinstance(a, str):
        if a != b or type(a) is not type(b):
            raise Differ(f"{path}: {a!r} vs {b!r}")
        return
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        d = angle_difference(a, b) if path.endswith(".yaw") else abs(a - b)
        if not d <= tolerance:
            raise Differ(f"{path}: {a!r} vs {b!r} (|difference| {d:.3g} > {tolerance:g})")
        top = path.split(".")[1].split("[")[0]
        largest[top] = max(largest.get(top, 0.0), d)
        return
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            raise Differ(f"{path}: {len(a)} vs {len(b)} elements")
        for i, (x, y) in enumerate(zip(a, b)):
            walk(x, y, f"{path}[{i}]", tolerance, largest)
        return
    if isinstance(a, dict) and isinstance(b, dict):
        if set(a) != set(b):
            raise Differ(f"{path}: keys {sorted(set(a) ^ set(b))} only in one file")
        for key in a:
            if key not in IGNORED_KEYS:
                walk(a[key], b[key], f"{path}.{key}", tolerance, largest)
        return
    raise Differ(f"{path}: {type(a).__name__} vs {type(b).__name__}")


def lower_bound(c):
    """The certificate's rigorous lower bound: dual_objective less bound_error (what rounding can
    have raised it by; absent or null in results written before it existed, then taken as 0)."""
    return c["dual_objective"] - (c.get("bound_error") or 0.0)


def same_optimum(a, b, tolerance, largest):
    """Both certify the same optimal value: each run's optimum lies in
    [dual_objective - bound_error, objective] (the solver stops at a relative gap of 1e-9, so the
    objectives alone may differ by that much), and the two intervals overlap to the tolerance,
    relative to the value."""
    for c in (a, b):
        if c.get("objective") is None or c.get("dual_objective") is None:
            raise Differ(f"$.certificate: no objective or dual objective in {c}")
    scale = max(1.0, abs(a["objective"]), abs(b["objective"]))
    separation = max(lower_bound(a), lower_bound(b)) - min(a["objective"], b["objective"])
    if separation > tolerance * scale:
        raise Differ(f"$.certificate: optimal value in [{lower_bound(a)!r}, {a['objective']!r}] vs "
                     f"[{lower_bound(b)!r}, {b['objective']!r}]: apart by {separation:.3g}")
    largest["certificate"] = max(largest.get("certificate", 0.0), abs(a["objective"] - b["objective"]) / scale)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("a")
    parser.add_argument("b")
    parser.add_argument("--tolerance", type=float, default=1e-9)
    args = parser.parse_args()
    try:
        docs = []
        for name in (args.a, args.b):
            with open(name, encoding="utf-8") as f:
                docs.append(json.load(f))
    except (OSError, ValueError) as e:
        print(f"compare_results: {e}")
        return 2
    largest = {}
    not_unique = [any(text in str(doc.get("reason", "")) for text in NOT_UNIQUE) for doc in docs]
    try:
        if not_unique[0] != not_unique[1]:
            raise Differ(f"$.reason: {docs[0].get('reason')!r} vs {docs[1].get('reason')!r}")
        if all(not_unique):
            for key in COMPARED_WHEN_NOT_UNIQUE:
                walk(docs[0].get(key), docs[1].get(key), f"$.{key}", args.tolerance, largest)
            same_optimum(docs[0]["certificate"], docs[1]["certificate"], args.tolerance, largest)
            print(f"equal: largest |difference| {max(largest.values(), default=0.0):.3g} "
                  "(optimum not unique: status and optimal value compared, the arbitrary poses not)")
            return 0
        walk(docs[0], docs[1], "$", args.tolerance, largest)
    except Differ as e:
        print(f"DIFFER {e}")
        return 1
    overall = max(largest.values(), default=0.0)
    parts = ", ".join(f"{k} {v:.3g}" for k, v in sorted(largest.items()) if v > 0)
    print(f"equal: largest |difference| {overall:.3g}" + (f" ({parts})" if parts else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
