"""Render the LaneNet dataset (lanekeep/evaluation/dataset.py): random worlds, exact labels, by
seed.

    python tools/make_dataset.py --out data/lanenet --train 320 --val 24 --test 24 [--workers 2]
    python tools/make_dataset.py --out /work/data/observer58 --seed 58 --cameras rear ...
    python tools/make_dataset.py --out /work/data/observer62m --seed 58 --cameras rear \
        --rear-mount-share 0.5 ...     # half the worlds seen near the loop's rear camera

Each world is one compressed shard (`SPLIT/world_NNNNN.npz`); a shard already there is kept,
so an interrupted run goes on where it stopped. `recipe.json` records the recipe and counts:
the same recipe and seed give the same shards, bit for bit, on the same machine.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import sys
import time
from pathlib import Path

import lanekeep  # noqa: F401  (first: it pins numpy's, torch's and OpenCV's kernels)

# isort: split
import numpy as np

from lanekeep.core.files import atomic_path
from lanekeep.evaluation.dataset import CAMERAS, DatasetRecipe, make_shard, shard_path, write_recipe


def _one(job: tuple[DatasetRecipe, str, int, str]) -> tuple[str, int, float]:
    recipe, split, index, root = job
    t0 = time.perf_counter()
    path = shard_path(Path(root), split, index)
    arrays = make_shard(recipe, split, index)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:  # a shard is complete or absent
        np.savez_compressed(tmp, **arrays)
    return split, index, time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", required=True, help="dataset folder")
    parser.add_argument("--train", type=int, default=320, help="training worlds")
    parser.add_argument("--val", type=int, default=24, help="validation worlds")
    parser.add_argument("--test", type=int, default=24, help="test worlds")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--sequences-per-world", type=int, default=6)
    parser.add_argument("--frames", type=int, default=3)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--cameras", choices=("both", "front", "rear"), default="both",
                        help="the cameras each sequence is rendered by (rear: a rear-only "
                             "model's data, without the front's render cost)")
    parser.add_argument("--rear-mount-share", type=float, default=0.0, metavar="P",
                        help="share of worlds whose cameras are mounted near the car's own rear "
                             "camera (a rear-only model's deployment camera) instead of the "
                             "world's draw (default 0)")
    args = parser.parse_args(argv)
    from tqdm import tqdm

    cameras = CAMERAS if args.cameras == "both" else (args.cameras,)
    recipe = DatasetRecipe(seed=args.seed, sequences_per_world=args.sequences_per_world,
                           frames=args.frames, cameras=cameras,
                           rear_mount_share=args.rear_mount_share)
    counts = {"train": args.train, "val": args.val, "test": args.test}
    root = Path(args.out)
    write_recipe(root, recipe, counts)
    jobs = [(recipe, split, i, str(root)) for split, n in counts.items() for i in range(n)
            if not shard_path(root, split, i).exists()]
    start = time.perf_counter()
    ctx = mp.get_context("spawn")  # EGL contexts do not survive fork
    with ctx.Pool(args.workers, maxtasksperchild=20) as pool, \
            tqdm(total=len(jobs), unit="world", desc="rendering") as bar:
        for _ in pool.imap_unordered(_one, jobs):
            bar.update()
    print(f"{len(jobs)} worlds in {time.perf_counter() - start:.0f} s -> {root}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
