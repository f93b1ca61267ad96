"""``mbsynth robots``: the robots example-robot-data ships."""

import json

from ..robots.validate import robot_table


def run(args):
    rows = robot_table()
    if args.json:
        print(json.dumps({"robots": [{"name": n, "urdf": p, "links": k, "movable_joints": j, "pinocchio": ok}
                                     for n, p, k, j, ok in rows]}, indent=2))
        return 0
    if not rows:
        print("no robots: install the example-robot-data package")
        return 0
    print(f"{'robot':<28} {'links':>5} {'joints':>6}  pinocchio  urdf")
    for name, path, links, joints, ok in rows:
        print(f"{name:<28} {links:>5} {joints:>6}  {'loads' if ok else 'FAILS':<9}  {'/'.join(path.split('/')[-3:])}")
    return 0
