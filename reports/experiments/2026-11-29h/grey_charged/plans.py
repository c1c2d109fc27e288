"""Each capture's plan and result in two rows files (reports/captures/cpu_*.json): the resolution bounds, the
step the plan chose, the final grid (after any memory cap), steps, samples a ray and held-out PSNR.

    python reports/experiments/2026-11-29h/grey_charged/plans.py BEFORE.json AFTER.json
"""
import json
import sys


def plan_of(run):
    """(plan, steps) of a row: rows collected before 2026-11-28 keep the plan at the top level."""
    if "schedule" in run:
        return run["schedule"]["plan"], run["schedule"]["steps_full"]
    return run["plan"], run.get("steps")


def line(name, run):
    plan, steps = plan_of(run)
    b = plan.get("resolution_bounds", {})
    return (f"  {name}: {run['held_out']['psnr']:.3f} dB, bounds observations {b.get('observations')} / memory "
            f"{b.get('memory')}, kernel_scale {plan.get('kernel_scale', 1.0)}, step {plan.get('step_voxels')} voxel, "
            f"planned {plan.get('final_resolution')} -> grid {run['grid']['full'][0]}, {steps} steps, "
            f"{run['evaluated_samples_per_ray']:.0f} samples a ray")


def main(before_path, after_path):
    with open(before_path) as f, open(after_path) as g:
        before, after = json.load(f)["runs"], json.load(g)["runs"]
    for capture in after:
        print(capture)
        if capture in before:
            print(line("before", before[capture]))
        print(line("after", after[capture]))


if __name__ == "__main__":
    if len(sys.argv) != 3:
        raise SystemExit(__doc__.strip().splitlines()[3].strip())
    main(*sys.argv[1:])
