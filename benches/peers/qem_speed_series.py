#!/usr/bin/env python3
"""QEM time and peak memory against meshoptimizer, as interleaved rounds with medians.

    cargo build --release -p meshgnn-graph --example qem
    target/release/examples/qem --make-bumpy 8 bench-data/bumpy8.ply
    python3 benches/peers/qem_speed_series.py bench-data/bumpy8.ply --ratios 0.1,0.01 \
        --rounds 5 [--build LABEL=PATH ...]

Each round runs, for every ratio, every build of our `qem` example (default: the one in
target/release; `--build` adds others, e.g. the previous commit's, so a change is timed in the
same minutes as its baseline) and meshoptimizer's `simplify` through the first build's
`--meshopt`. Interleaving keeps a burst of load on this shared machine from landing on one
method only. Times cover the decimation (not the file loading); peak memory is the whole
process's maximum resident set (`/usr/bin/time -f %M`), file loading included.
Prints one line per run, then per ratio and method the median time, median peak memory and
their ratios to meshoptimizer's.
"""
import argparse
import json
import os
import statistics
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def run(binary, mesh, ratio, meshopt):
    """Seconds and peak resident kilobytes of one decimation."""
    with tempfile.NamedTemporaryFile("r", suffix=".txt") as rss:
        args = ["/usr/bin/time", "-f", "%M", "-o", rss.name, binary, mesh, "--ratio", str(ratio),
                "--no-metrics"] + (["--meshopt"] if meshopt else [])
        out = subprocess.run(args, check=True, capture_output=True, text=True).stdout
        peak_kb = int(rss.read().split()[-1])
    return json.loads(out.strip().splitlines()[-1])["seconds"], peak_kb


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("mesh", nargs="?", default=os.path.join(ROOT, "bench-data", "bumpy8.ply"))
    parser.add_argument("--ratios", default="0.1,0.01")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--build", action="append", default=[], metavar="LABEL=PATH")
    args = parser.parse_args()
    builds = [("meshgnn", os.path.join(ROOT, "target", "release", "examples", "qem"))]
    builds += [tuple(b.split("=", 1)) for b in args.build]
    ratios = [float(r) for r in args.ratios.split(",")]

    results = {}
    for round_ in range(args.rounds):
        for ratio in ratios:
            runs = [(label, path, False) for label, path in builds]
            runs.append(("meshopt", builds[0][1], True))
            for label, path, meshopt in runs:
                seconds, peak_kb = run(path, args.mesh, ratio, meshopt)
                results.setdefault((ratio, label), []).append((seconds, peak_kb))
                print(f"round {round_ + 1} ratio {ratio} {label}: {seconds:.3f} s, "
                      f"{peak_kb / 1024:.0f} MiB", flush=True)

    print("\nratio  method      median s  x meshopt  median MiB  x meshopt")
    for ratio in ratios:
        reference = results[(ratio, "meshopt")]
        ref_s = statistics.median(s for s, _ in reference)
        ref_kb = statistics.median(m for _, m in reference)
        for label in [b[0] for b in builds] + ["meshopt"]:
            series = results[(ratio, label)]
            s = statistics.median(x for x, _ in series)
            kb = statistics.median(m for _, m in series)
            print(f"{ratio:<6} {label:<11} {s:8.3f}  {s / ref_s:9.2f}  {kb / 1024:10.0f}  "
                  f"{kb / ref_kb:9.2f}")


if __name__ == "__main__":
    main()
