"""The Dask batch example on a 2-worker LocalCluster: every file reported, failures too."""

import json
import shutil
import subprocess
import sys

from conftest import FIXTURES, REPO


def test_batch_simplifies_every_file_and_reports_the_broken_one(tmp_path):
    inputs = tmp_path / "in"
    inputs.mkdir()
    for name in ("icosphere_trimesh.obj", "sphere_open3d.ply", "box_trimesh.off"):
        shutil.copy(FIXTURES / "peer" / name, inputs / name)
    (inputs / "broken.obj").write_text("f 1 2 3\n")
    summary = tmp_path / "summary.json"
    run = subprocess.run(
        [sys.executable, REPO / "examples" / "python" / "batch_simplify_dask.py", inputs,
         tmp_path / "out", "--ratio", "0.5", "--workers", "2", "--summary", summary],
        capture_output=True, text=True, timeout=300,
    )
    assert run.returncode == 1, run.stderr  # one file failed
    report = json.loads(summary.read_text())
    assert report["files"] == 4 and report["failed"] == 1 and report["workers"] == 2
    by_name = {r["input"].rsplit("/", 1)[-1]: r for r in report["results"]}
    assert "broken.obj" in by_name["broken.obj"]["failure"]
    assert by_name["icosphere_trimesh.obj"]["output_faces"] == 160
    assert by_name["icosphere_trimesh.obj"]["stop_reason"] == "target_reached"
    assert by_name["sphere_open3d.ply"]["output_faces"] == 264
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [
        "box_trimesh.off", "icosphere_trimesh.obj", "sphere_open3d.ply"
    ]
