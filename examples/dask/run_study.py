#!/usr/bin/env python3
"""Run one mtsim study (sweep, sweep --feasibility or batch) on a Dask cluster.

The study is split into N shards (`--shard K/N`); each shard is one Dask task that runs
`mtsim` in a scratch folder on its worker and returns the shard file's bytes, so workers
need no shared file system (only the mtsim binary and the scenario files at the same
paths). The client writes the N shard files and joins them with `mtsim merge`: the result
is byte-identical to running the study on one machine.

    # local cluster of 2 workers
    python3 examples/dask/run_study.py --shards 8 --out study -- \
        sweep scenarios/cone-15-10.toml --vary center_y --from -30 --to -15 --step 0.5
    # a real cluster: give the scheduler's address
    python3 examples/dask/run_study.py --scheduler tcp://10.0.0.5:8786 --shards 64 ...

Needs: pip install "dask[distributed]" pandas pyarrow
"""

import argparse
import os
import pathlib
import subprocess
import sys
import tempfile


def run_shard(mtsim, study_args, k, n, cwd):
    """Runs shard k/n in a scratch folder; returns (file name, bytes) of its shard file."""
    with tempfile.TemporaryDirectory(prefix="mtsim-shard-") as out:
        cmd = [mtsim, *study_args, "--shard", f"{k}/{n}", "-o", out]
        done = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
        if done.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd)} failed ({done.returncode}): {done.stderr}")
        (name,) = [p for p in os.listdir(out) if p.endswith(".json")]
        return name, pathlib.Path(out, name).read_bytes()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scheduler", help="address of a running Dask scheduler (default: a LocalCluster)")
    ap.add_argument("--workers", type=int, default=2, help="workers of the LocalCluster (default 2)")
    ap.add_argument("--shards", type=int, default=8, help="number of shards N (default 8)")
    ap.add_argument("--mtsim", default="mtsim", help="the mtsim binary, as the workers find it")
    ap.add_argument("--out", required=True, help="output folder: shards/ and the merged files")
    ap.add_argument("study", nargs=argparse.REMAINDER, help="-- then the mtsim study, e.g. sweep SCENARIO --vary ...")
    a = ap.parse_args()
    study = a.study[1:] if a.study[:1] == ["--"] else a.study
    if not study or study[0] not in ("sweep", "batch"):
        ap.error("give the study after --: sweep ... or batch ...")

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
        futures = [client.submit(run_shard, a.mtsim, study, k, a.shards, cwd, pure=False)
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
    merged = subprocess.run([a.mtsim, "merge", *files, "-o", str(out)], capture_output=True, text=True)
    sys.stdout.write(merged.stdout)
    if merged.returncode not in (0, 1):  # 1: batch found violations
        sys.stderr.write(merged.stderr)
        sys.exit(merged.returncode)

    # The Parquet table is read directly, as any dataframe engine would.
    import pandas as pd
    for table in sorted(out.glob("*.parquet")):
        df = pd.read_parquet(table)
        print(f"{table.name}: {len(df)} rows, columns {', '.join(df.columns)}", file=sys.stderr)
    sys.exit(merged.returncode)


if __name__ == "__main__":
    main()
