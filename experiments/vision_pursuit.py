"""Animat vision, seed 003 section 3: Fig. 7 (gaze angles over 100 frames of pursuit), Fig. 8
(the retinal sequence) and a success table over seeds (random prey paths, start distances).

Writes docs/figures/vision_fig7_gaze.png, vision_fig8_frames.png and vision_pursuit.json.
Run: python experiments/vision_pursuit.py [--seeds 20] [--first 0] [--seconds 60]
[--skills built-in|learned|DIR]
"""

from __future__ import annotations

import argparse

import numpy as np

from zoetic.io import write_json
from zoetic.perception.pursuit import make_chase, run_chase, summarize
from zoetic.reproduce import figures_dir
from zoetic.viz.gaze import plot_frames, plot_gaze

OUT = figures_dir()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first", type=int, default=0, help="the first seed (figures from seed 0)")
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument(
        "--skills", default="built-in", help="built-in, learned or a repertoire's directory"
    )
    args = ap.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    rows = []
    for seed in range(args.first, args.first + args.seeds):
        chase = make_chase(seed, skills=args.skills)
        res = run_chase(chase, args.seconds, seed=seed)
        s = summarize(res, chase.predator.gaze.spec) | {"seed": seed}
        rows.append(s)
        print(seed, s)
        if seed == 0:
            plot_gaze(res.log[:100], OUT / "vision_fig7_gaze.png")
            plot_frames(res.log, OUT / "vision_fig8_frames.png")
    caught = [r for r in rows if r["caught"]]
    table = {
        "seeds": args.seeds,
        "first_seed": args.first,
        "seconds": args.seconds,
        "skills": args.skills,
        "caught": len(caught),
        "mean_time_to_catch_s": float(np.mean([r["time_to_catch_s"] for r in caught]))
        if caught
        else None,
        "mean_foveated_fraction": float(np.mean([r["foveated_fraction"] for r in rows])),
        "distractor_fixations": int(sum(r["distractor_fixations"] for r in rows)),
        "seeds_with_distractor_fixations": int(sum(r["distractor_fixations"] > 0 for r in rows)),
        "mean_gaze_correlation_theta": float(np.mean([r["gaze_correlation_theta"] for r in rows])),
        "runs": rows,
    }
    # pitching with the fins: seed 0's prey started 0.6 m above or below, fins on and off
    pitch = []
    for height in (0.6, -0.6):
        for gain in (2.0, 0.0):
            chase = make_chase(0, prey_height=height, skills=args.skills)
            chase.predator.fin_gain = gain
            res = run_chase(chase, 15.0, seed=0)
            s = summarize(res, chase.predator.gaze.spec)
            pitch.append({"prey_height_m": height, "fin_gain": gain, "caught": s["caught"],
                          "time_to_catch_s": s["time_to_catch_s"],
                          "foveated_fraction": s["foveated_fraction"]})  # fmt: skip
            print(pitch[-1])
    table["pitch_seed0_15s"] = pitch
    write_json(OUT / "vision_pursuit.json", table)
    print({k: v for k, v in table.items() if k != "runs"})


if __name__ == "__main__":
    main()
