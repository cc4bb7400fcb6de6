"""`spherecal tool`: Put another tool on a calibrated arm (calibrate with the ball, work with the gripper)."""

from __future__ import annotations

import argparse

from spherecal.options import check_robot_names, finite, refuse_given

HELP = "Put another tool on a calibrated arm: a new robot file with the tool point replaced."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal tool`."""
    parser.add_argument("robot", metavar="CAL.yaml", help="calibrated robot file")
    tool = parser.add_mutually_exclusive_group(required=True)
    tool.add_argument("--offset", nargs=3, type=finite, metavar=("X", "Y", "Z"),
                      help="the new tool's nominal point in the last DH frame [m]: the frame that turns with the "
                      "last joint, z along its axis; for a URDF arm it is fixed to the child link of the last "
                      "revolute joint (the last of 'urdf: links:' in CAL.yaml; the command names it), though not "
                      "at that link's origin in general. From that frame's origin and along its axes, which are "
                      "not the flange's in general (where the flange sits in that frame depends on the arm and on "
                      "how its model was built). Simplest: the old tool's nominal point "
                      "(the ball's, calibration.nominal_tool in CAL.yaml; the command prints both points) plus the "
                      "new tool's offset from the ball, e.g. its z + 0.1 for a tool 0.1 m further along z; or take "
                      "the point from the arm's URDF with --urdf and --tip-link. The calibration's correction of the "
                      "old tool point is carried over and added. Example, the embedded Panda: its flange is at "
                      "0 0 0.107 in that frame, so a TCP 0.1034 m past the flange is 0 0 0.2104")
    tool.add_argument("--urdf", default=None, metavar="TOOL.urdf",
                      help="a URDF of the same arm with the new tool (its last DH frame must be the calibrated "
                      "file's); --tip-link names the tool link")
    parser.add_argument("--tip-link", default=None, metavar="NAME", help="with --urdf: the link at the new tool point")
    parser.add_argument("--base-link", default=None, metavar="NAME", help="with --urdf: the arm's base link")
    parser.add_argument("--adapter", action=argparse.BooleanOptionalAction, default=None,
                        help="needed only when the calibration's samples put the ball more than 10 mm from its robot "
                        "file's tool (calibration.samples_tool; calibrate warned): --adapter if an adapter or sensor "
                        "between the flange and every tool put it there (the offset is carried to the new tool), "
                        "--no-adapter if it is the ball's own mount or the calibration's --tip-link named another "
                        "link (not carried)")
    parser.add_argument("--out", required=True, metavar="FILE", help="the new robot file (written atomically)")


def run(args: argparse.Namespace) -> int:
    """Load, put the tool on, write; nothing is written on an error."""
    from spherecal.correction import dump_robot, load_robot
    from spherecal.correction.files.tools import put_tool
    from spherecal.options import planned_outputs

    if args.urdf is None:
        refuse_given(args, ("tip_link", "base_link"), "only with --urdf (the link of the new tool in its URDF)")
    check_robot_names(args, robot="CAL.yaml")  # an unknown robot name, by its positional CAL.yaml
    outputs = planned_outputs(args, {"--out": args.out})  # never over an input, named as YAML
    model = load_robot(args.robot)
    from spherecal.correction.files.robot_file import forced_calibration

    forced = forced_calibration(model)
    if forced:  # the new file carries the verdict; say it now, as export and validate do
        import warnings

        warnings.warn(forced, stacklevel=1)
    swap, payload = put_tool(model, args.offset, args.urdf, args.tip_link, args.base_link, source=args.robot,
                            adapter=args.adapter)
    header = (f"spherecal tool: {args.robot} with the tool at {swap.model.tool.round(6).tolist()} m (frame n)\n"
              + _provenance(args))
    with outputs:
        path = outputs.write_text(args.out, dump_robot(swap.model, header=header))
    print(f"spherecal tool: wrote {path}: tool point {swap.model.tool.round(6).tolist()} m in the last frame "
          f"(was {model.tool.round(6).tolist()})")
    print(f"spherecal tool: {_nominal_points(model, swap.model)}")
    print(f"spherecal tool: the last frame: {last_frame(model)}")
    print(f"spherecal tool: {swap.note}")
    print(f"spherecal tool: {payload}")
    return 0


def _provenance(args: argparse.Namespace) -> str:
    """The comment lines of the new file's provenance: this command, versions, and its inputs (CAL.yaml, --urdf)
    with their SHA-256 (the file's calibration.provenance is the calibration's, not this swap's)."""
    from spherecal.correction.files.provenance import comment_block, provenance
    from spherecal.options import recorded_options

    return comment_block(provenance(None, recorded_options(args)))


def last_frame(model) -> str:
    """Which frame the tool point is given in, for the user: the last DH frame, and for a model converted from a URDF
    (its ``urdf`` block) the link it turns with, the child of the last revolute joint (a review: neither --help nor
    the output said which link that frame is). Its origin is on that joint's axis where the DH common normal puts
    it, the link's own origin only in some URDFs (the Panda's panda_link7; 105 mm along z from the Gen3 lite's
    end_effector_link): said, not hidden."""
    n = model.n_joints
    urdf = model.extras.get("urdf")
    links = urdf.get("links") if isinstance(urdf, dict) else None
    if not isinstance(links, list) or len(links) != n or not all(isinstance(name, str) for name in links):
        return f"the last DH frame (frame {n} of the robot file; it records no URDF link)"
    names = model.extras.get("joint_names")
    joint = f" {names[-1]}" if isinstance(names, list) and len(names) == n and isinstance(names[-1], str) else ""
    return (f"the last DH frame (frame {n}), fixed to link {links[-1]}, the child of the last revolute "
            f"joint{joint}: z along that joint's axis, its origin on the axis, not necessarily the link's origin")


def _nominal_points(model, swapped) -> str:
    """One line: the calibration's nominal tool point (``calibration.nominal_tool``) and the new tool's [m], in the
    last frame, the points ``--offset`` is compared with (before the calibration's correction is added)."""
    import numpy as np

    block = model.extras.get("calibration")
    recorded = block.get("nominal_tool") if isinstance(block, dict) else None
    swap = swapped.extras["tool_swap"]
    new = np.asarray(swap["tool"], dtype=float) - np.asarray(swap["carried_correction"], dtype=float)
    if recorded is None:
        return (f"nominal tool point [m] in the last frame: the new tool's {new.round(6).tolist()}; the calibrated "
                "file records no calibration.nominal_tool (the point is put as given, no correction carried)")
    old = np.asarray(recorded, dtype=float).round(6).tolist()
    return (f"nominal tool points [m] in the last frame: the calibration's {old} (calibration.nominal_tool), "
            f"the new tool's {new.round(6).tolist()}")
