#!/usr/bin/env python3
"""Run one mtsim study (sweep, sweep --feasibility, batch, study) on a Dask cluster.

The study is split into N shards (`--shard K/N`); each shard is one Dask task that runs
the study through the mtsim Python package (`mtsim.run_command`, the command line in the
worker's process) in a scratch folder and returns the shard file's bytes, so workers need
the package (`pip install .` from this repository) and the scenario files at the same
paths, but neither the mtsim binary nor a shared file system. The client writes the N
shard files and joins them with `mtsim merge`, again through the package: the result is
byte-identical to running the study on one machine.

    # local cluster of 2 workers
    python3 examples/dask/run_study.py --shards 8 --out study -- \\
        sweep scenarios/cone-15-10.toml --vary center_y --from -30 --to -15 --step 0.5
    # a real cluster: give the scheduler's address
    python3 examples/dask/run_study.py --scheduler tcp://10.0.0.5:8786 --shards 64 ...

Needs: pip install . "dask[distributed]" pandas pyarrow
"""

import argparse
import os
import pathlib
import sys
import tempfile

import mtsim


def run_shard(study_args, k, n, cwd):
    """Runs shard k/n in a scratch folder; returns (file name, bytes) of its shard file."""
    with tempfile.TemporaryDirectory(prefix="mtsim-shard-") as out:
        os.chdir(cwd)
        args = [*study_args, "--shard", f"{k}/{n}", "-o", out]
        code = mtsim.run_command(args)
        if code != 0:
            raise RuntimeError(f"mtsim {' '.join(args)} failed with exit code {code} "
                               "(its message is in the worker's log)")
        (name,) = [p for p in os.listdir(out) if p.endswith(".json")]
        return name, pathlib.Path(out, name).read_bytes()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scheduler", help="address of a running Dask scheduler (default: a LocalCluster)")
    ap.add_argument("--workers", type=int, default=2, help="workers of the LocalCluster (default 2)")
    ap.add_argument("--shards", type=int, default=8, help="number of shards N (default 8)")
    ap.add_argument("--out", required=True, help="output folder: shards/ and the merged files")
    ap.add_argument("study", nargs=argparse.REMAINDER, help="-- then the mtsim study, e.g. sweep SCENARIO --vary ...")
    a = ap.parse_args()
    study = a.study[1:] if a.study[:1] == ["--"] else a.study
    if not study or study[0] not in ("sweep", "batch", "study"):
        ap.error("give the study after --: sweep ..., batch ... or study ...")

    from dask.distributed import Client, LocalCluster

    if a.scheduler:
        client = Client(a.scheduler)
        cluster = None
    else:
        cluster = LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
    try:
        cwd = os.getcwd()
        futures = [client.submit(run_shard, study, k, a.shards, cwd, pure=False)
                   for k in range(1, a.shards + 1)]
        results = client.gather(futures)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()

    out = pathlib.Path(a.out)
    shards = out / "shards"
    shards.mkdir(parents=True, exist_ok=True)
    files = []
    for name, data in results:
        (shards / name).write_bytes(data)
        files.append(str(shards / name))
    code = mtsim.run_command(["merge", *files, "-o", str(out)])
    if code not in (0, 1):  # 1: batch found violations
        sys.exit(code)

    # The Parquet table is read directly, as any dataframe engine would.
    import pandas as pd
    for table in sorted(out.glob("*.parquet")):
        df = pd.read_parquet(table)
        print(f"{table.name}: {len(df)} rows, columns {', '.join(df.columns)}", file=sys.stderr)
    sys.exit(code)


if __name__ == "__main__":
    main()
