#!/usr/bin/env python3
"""How low can a label-driven expression generator go on a `synth faces` set?

The generator of thesis ch. 4 (eq. 4.1) sees only the label signal, never the subject, so its
best possible prediction of a test frame is the mean displacement of all training frames with
the same label history. This script estimates that floor from above with k-nearest-neighbour
means of the training displacements (frame − the subject's neutral), keyed on what is known
about each test frame, from the label alone to oracles that know more than any label does:

  amplitude                         the frame's label (expression, motion × intensity)
  label history                     what a causal model can know from the labels so far: the
                                    label, the previous frame's and the largest yet
  motion + intensity                both factors of the label (the intensity is only known
                                    to a causal model once the apex is reached)
  motion + intensity + extremeness  also the sequence's hidden extremeness

Error: mean per-vertex Euclidean distance (mm) over every frame of the test sequences, the
figure of `express eval`. Usage (numpy only):

  python3 benches/scripts/expression_floor.py DATA [--json]
"""
import json
import os
import sys

import numpy as np


def read_ply_vertices(path):
    data = open(path, "rb").read()
    header_end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:header_end].decode("ascii").splitlines()
    count = next(int(l.split()[2]) for l in header if l.startswith("element vertex"))
    assert "format binary_little_endian 1.0" in header, f"{path}: not binary PLY"
    return np.frombuffer(data, dtype="<f4", count=3 * count, offset=header_end).reshape(count, 3)


def frames(root, dataset, split):
    labels = dataset["labels"]
    names = [n for n in dataset["splits"][split] if "label" in labels.get(n, {})]
    names.sort(key=lambda n: (labels[n]["subject"], labels[n]["expression"], labels[n]["frame"]))
    neutral, rows = {}, []
    for name in names:
        meta = labels[name]
        s = meta["subject"]
        if s not in neutral:
            neutral[s] = read_ply_vertices(os.path.join(root, f"face_{s:03d}_neutral.ply"))
        rows.append((read_ply_vertices(os.path.join(root, name)) - neutral[s], meta))
    displacements = np.stack([r[0] for r in rows]).astype(np.float32)
    # the label history of each frame within its sequence (subject, expression), frame order
    previous, largest, last = [], [], {}
    for _, meta in rows:
        sequence = (meta["subject"], meta["expression"])
        a = max(meta["label"])
        prev_a, top = last.get(sequence, (0.0, 0.0))
        previous.append(prev_a)
        largest.append(max(top, a))
        last[sequence] = (a, max(top, a))
    keys = {
        "previous": np.array(previous),
        "largest": np.array(largest),
        "expression": np.array([r[1]["expression"] for r in rows]),
        "amplitude": np.array([max(r[1]["label"]) for r in rows]),
        "motion": np.array([r[1]["motion"] for r in rows]),
        "intensity": np.array([r[1]["intensity"] for r in rows]),
        "extremeness": np.array([r[1]["extremeness"] for r in rows]),
    }
    return displacements, keys


def knn_floor(train, test, fields, k):
    (dtr, ktr), (dte, kte) = train, test
    total = 0.0
    for i in range(len(dte)):
        same = np.flatnonzero(ktr["expression"] == kte["expression"][i])
        distance = np.sqrt(sum((ktr[f][same] - kte[f][i]) ** 2 for f in fields))
        nearest = same[np.argsort(distance, kind="stable")[:k]]
        prediction = dtr[nearest].mean(axis=0)
        total += np.linalg.norm(prediction - dte[i], axis=-1).mean()
    return total / len(dte)


def main():
    root = sys.argv[1]
    dataset = json.load(open(os.path.join(root, "dataset.json")))
    train, test = frames(root, dataset, "train"), frames(root, dataset, "test")
    keys = {
        "amplitude": ["amplitude"],
        "label_history": ["amplitude", "previous", "largest"],
        "motion_intensity": ["motion", "intensity"],
        "motion_intensity_extremeness": ["motion", "intensity", "extremeness"],
    }
    result = {
        "train_frames": len(train[0]),
        "test_frames": len(test[0]),
        "zero_mm": float(np.linalg.norm(test[0], axis=-1).mean()),
        "floor_mm": {
            name: {str(k): knn_floor(train, test, fields, k) for k in (5, 10, 20, 40)}
            for name, fields in keys.items()
        },
    }
    if "--json" in sys.argv:
        print(json.dumps(result))
        return
    print(f"{result['train_frames']} training frames, {result['test_frames']} test frames")
    print(f"predicting no motion: {result['zero_mm']:.4f} mm")
    for name, by_k in result["floor_mm"].items():
        row = "  ".join(f"k={k}: {v:.4f}" for k, v in by_k.items())
        print(f"{name:30s} {row} mm")


if __name__ == "__main__":
    main()
