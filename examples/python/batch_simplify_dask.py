#!/usr/bin/env python3
"""Simplify every mesh file of a folder on a Dask cluster: one task per file.

    python examples/python/batch_simplify_dask.py INPUT_DIR OUTPUT_DIR --ratio 0.1 \
        [--faces N] [--scheduler tcp://host:8786] [--workers 2] [--summary summary.json]

Without ``--scheduler`` a ``LocalCluster`` with ``--workers`` single-threaded workers runs on
this machine. Each output is written under the input's name in OUTPUT_DIR (atomically, never
over an input). A file that fails is reported with its error and never stops the batch; the
summary (printed, and written to ``--summary`` when given) lists every file, and the exit code
is 1 when any failed. The task function is plain Python over ``meshgnn``, so the same function
runs unchanged inside a Ray task or a Spark ``mapPartitions``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

MESH_SUFFIXES = {".obj", ".ply", ".off", ".glb", ".gltf"}


def simplify_file(input_path: str, output_path: str, ratio, faces) -> dict:
    """Reads, simplifies and writes one mesh; returns its record (never raises)."""
    import meshgnn

    start = time.perf_counter()
    try:
        V, F = meshgnn.read_mesh(input_path)
        V2, F2, info = meshgnn.simplify(V, F, ratio=ratio, faces=faces, return_info=True)
        meshgnn.write_mesh(output_path, V2, F2)
    except (ValueError, OSError) as error:
        return {"input": input_path, "failure": str(error)}
    return {
        "input": input_path,
        "output": output_path,
        "input_faces": info["input_faces"],
        "output_faces": info["output_faces"],
        "vertices": int(len(V2)),
        "error": info["error"],
        "stop_reason": info["stop_reason"],
        "seconds": time.perf_counter() - start,
    }


def mesh_files(folder: Path) -> list:
    return sorted(p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in MESH_SUFFIXES)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("input_dir", type=Path)
    parser.add_argument("output_dir", type=Path)
    target = parser.add_mutually_exclusive_group(required=True)
    target.add_argument("--ratio", type=float, help="fraction of the faces to keep, in (0, 1]")
    target.add_argument("--faces", type=int, help="face count to keep")
    parser.add_argument("--scheduler", help="address of a running dask scheduler")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                        help="workers of the LocalCluster when no --scheduler is given")
    parser.add_argument("--summary", type=Path, help="also write the JSON summary here")
    args = parser.parse_args(argv)

    from dask.distributed import Client, LocalCluster, as_completed

    inputs = mesh_files(args.input_dir)
    if not inputs:
        print(f"error: {args.input_dir}: no mesh files (.obj .ply .off .glb .gltf)",
              file=sys.stderr)
        return 2
    args.output_dir.mkdir(parents=True, exist_ok=True)
    if args.output_dir.resolve() == args.input_dir.resolve():
        print("error: the output folder is the input folder: the inputs would be overwritten",
              file=sys.stderr)
        return 2

    start = time.perf_counter()
    cluster = None
    if args.scheduler:
        client = Client(args.scheduler)
    else:
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1,
                               processes=True, dashboard_address=None)
        client = Client(cluster)
    try:
        futures = {
            client.submit(simplify_file, str(p), str(args.output_dir / p.name),
                          args.ratio, args.faces, pure=False): p
            for p in inputs
        }
        records = []
        for done, future in enumerate(as_completed(futures), 1):
            try:
                records.append(future.result())
            except Exception as error:  # a worker lost, a task killed: reported, not fatal
                records.append({"input": str(futures[future]), "failure": f"task failed: {error}"})
            print(f"\r{done}/{len(futures)} files", end="", file=sys.stderr, flush=True)
        print(file=sys.stderr)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()

    records.sort(key=lambda r: r["input"])
    failed = [r for r in records if "failure" in r]
    summary = {
        "files": len(records),
        "failed": len(failed),
        "seconds": time.perf_counter() - start,
        "workers": args.workers if cluster is not None else None,
        "results": records,
    }
    text = json.dumps(summary, indent=1)
    print(text)
    if args.summary:
        partial = args.summary.with_name(args.summary.name + ".partial")
        partial.write_text(text + "\n")
        os.replace(partial, args.summary)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
