"""A calibrated model written into the user's own URDF: only joint origins change.

The calibrated arm keeps every link frame of the original URDF attached to the same joint
axis: for revolute joint ``k`` the pose ``M_k`` of its child link in DH frame ``k`` is taken
from the original file (converted with :func:`.urdf_to_dh.urdf_model`), and the child
link is placed at ``DH_k^cal(q = 0) M_k``. Joint ``k``'s ``<origin>`` is then what puts it
there from its parent link (fixed joints in between are kept as they are), and the fixed joint
into the tip link gets the calibrated tool point. Nothing else in the text is touched: the
new ``xyz``/``rpy`` values are substituted in place, comments, meshes, inertials, limits,
names, the gripper and the formatting stay byte for byte; one provenance comment is added
before ``<robot>``.
"""

from __future__ import annotations

import re
import warnings

import numpy as np

from ..chain import link_frames
from ..conversion import to_modified
from ..kinematics import tool_point
from ..model import RobotModel, geometric_part, matrix_rpy
from ..rigid import registered_errors
from ..tool import TIP_MOVED, arm_of, tip_moved
from .robot_file import RobotFileError
from .urdf_read import MOVABLE, UrdfTree, parse_urdf
from .urdf_to_dh import NearlyParallelAxesWarning, urdf_model
from .urdf_write import ExportError, _triple, provenance_comment, xml_comment

#: Largest tool-point distance [m] (after the best rigid fit) between the calibrated model and the
#: URDF's nominal arm: beyond it the URDF is another robot (a calibration moves millimetres).
SAME_ROBOT_TOL = 0.05
#: Another end of the chain nearer than the tip link to the calibrated tool point by more than this [m] is named
#: in a warning (within :data:`correction.tool.TIP_MOVED` a tip's move is taken as the calibration's correction).
CLOSER_END = 0.001

_COMMENT = re.compile(r"<!--.*?-->", re.S)
#: The two comments :func:`urdf_into` puts before ``<robot>`` (what it wrote, then the robot file's provenance), as
#: written: no ``--`` inside (:func:`.urdf_write.xml_comment`), so the first ``-->`` ends each.
_OUR_COMMENTS = re.compile(
    r"<!-- joint origins of [^\n]*? written by spherecal\n.*?-->\n"
    r"<!-- (?:provenance of the robot file\n.*?|calibration: none \(nominal or hand-written robot file\) )-->\n",
    re.S)
_JOINT_OPEN = re.compile(r"<joint\b[^>]*?\bname\s*=\s*([\"'])(.*?)\1[^>]*>", re.S)
_ORIGIN = re.compile(r"<origin\b[^>]*?/>", re.S)


def _masked(text: str) -> str:
    """``text`` with every comment blanked out (same length): searches skip commented-out XML."""
    return _COMMENT.sub(lambda m: " " * len(m.group(0)), text)


def _set_attribute(tag: str, name: str, value: str) -> str:
    pattern = re.compile(rf"(\b{name}\s*=\s*)([\"'])(.*?)\2", re.S)
    if pattern.search(tag):
        return pattern.sub(lambda m: f"{m.group(1)}{m.group(2)}{value}{m.group(2)}", tag, count=1)
    return tag[:-2].rstrip() + f' {name}="{value}"/>'


def replace_origins(text: str, origins: dict[str, np.ndarray], source: str = "<urdf>") -> str:
    """URDF text with the ``<origin>`` of the named joints set to the given poses, all else kept.

    Args:
        text: the URDF document.
        origins: joint name -> (4, 4) origin in its parent link frame [m].
        source: file name for error messages.
    """
    masked = _masked(text)
    edits: list[tuple[int, int, str]] = []
    for match in _JOINT_OPEN.finditer(masked):
        name = match.group(2)
        if name not in origins:
            continue
        end = masked.find("</joint>", match.end())
        if end < 0:
            raise ExportError(f"{source}: joint {name!r}: no closing </joint>")
        pose = origins[name]
        xyz, rpy = _triple(pose[:3, 3]), _triple(matrix_rpy(pose[:3, :3]))
        origin = _ORIGIN.search(masked, match.end(), end)
        if origin is None:
            indent = re.search(r"\n([ \t]*)<", masked[match.end():end])
            pad = "\n" + (indent.group(1) if indent else "  ")
            edits.append((match.end(), match.end(), f'{pad}<origin xyz="{xyz}" rpy="{rpy}"/>'))
        else:
            tag = _set_attribute(_set_attribute(text[origin.start():origin.end()], "xyz", xyz), "rpy", rpy)
            edits.append((origin.start(), origin.end(), tag))
    found = {m.group(2) for m in _JOINT_OPEN.finditer(masked)}
    missing = [name for name in origins if name not in found]
    if missing:
        raise ExportError(f"{source}: joint {missing[0]!r} not found in the text")
    for start, stop, new in sorted(edits, reverse=True):
        text = text[:start] + new + text[stop:]
    return text


def _check_same_arm(model: RobotModel, nominal: RobotModel, source: str, names: bool = True) -> None:
    """Refuse a URDF chain that is not the model's arm: joint count, joint names (when ``names``: the model was
    read from a description naming this URDF's links), tool points after the best rigid fit."""
    names = model.extras.get("joint_names") if names else None
    if model.n_joints != nominal.n_joints:
        raise ExportError(
            f"{source}: chain {nominal.extras['urdf']['base_link']!r} -> {nominal.extras['urdf']['tip_link']!r} "
            f"has {nominal.n_joints} revolute joints, the calibrated model {model.n_joints}"
        )
    if names is not None and list(names) != nominal.extras["joint_names"]:
        raise ExportError(
            f"{source}: joint names {nominal.extras['joint_names']} differ from the calibrated model's {list(names)}"
        )
    # a calibration of this URDF's tip whose samples put the ball elsewhere: the arms are compared alone, and with
    # the URDF's joint zeros (a calibration moves a zero by degrees, a real arm's are 1-3 deg off: dinova_2's 3 deg
    # put its tool points 51 mm from the URDF's; another robot differs in its lengths)
    error = _tool_point_gap(with_zeros_of(arm_of(model, nominal), nominal), nominal)
    if error > SAME_ROBOT_TOL:
        _refuse_new_tool(model, source, f"{nominal.extras['urdf']['tip_link']!r} is {error * 1e3:.0f} mm from it")
        raise ExportError(
            f"{source}: not the calibrated robot: tool points {error * 1e3:.0f} mm apart "
            f"(more than {SAME_ROBOT_TOL * 1e3:.0f} mm after the best rigid fit)"
        )


def _named_chain(links: dict) -> list[str]:
    """The base and tip links a model's ``extras["urdf"]`` names."""
    return [links[key] for key in ("base_link", "tip_link") if isinstance(links.get(key), str)]


def _end_of_another_description(model: RobotModel, tree: UrdfTree, links: dict, source: str) -> str:
    """For a calibrated file naming links this URDF lacks (a calibration of an embedded arm, or of another file of
    it): the one end of this URDF's chain at the model's tool point, with one warning that the joints are matched
    by geometry.

    Raises:
        ExportError: no end, or several, at the tool point (another arm, or no link at the calibrated tool).
    """
    chain = " -> ".join(map(repr, _named_chain(links)))
    ends = _ends_at(model, tree, None)
    if len(ends) != 1:
        raise ExportError(
            f"{source}: field 'tip_link': the calibrated file's chain {chain} is not in this URDF (robot "
            f"{tree.name!r}), and {'several' if ends else 'none'} of its chain's ends "
            f"{'are' if ends else 'is'} at the calibrated tool point: a URDF of another arm, or without a link at the "
            "calibrated tool?")
    warnings.warn(f"{source}: field 'tip_link': the calibrated file's chain {chain} is another description's (not in "
                  f"this URDF): written into its chain to {ends[0]!r}, the joints matched by their geometry, not their "
                  "names", stacklevel=3)
    return ends[0]


def _tip_at_the_ball(model: RobotModel, nominal: RobotModel, tree: UrdfTree, base_link: str | None,
                     source: str) -> RobotModel:
    """The chain to write: ``nominal``'s, unless the model is a calibration of its tip whose samples put the ball
    centimetres from it (:data:`TIP_MOVED`; a tip short of the ball, the flange or a gripper's TCP, with a sensor
    or adapter the description lacks). Then the one end of this URDF at the calibrated tool point, if any (MUKCa's
    ``ball_link``), with one warning; else the tip link itself, with one warning that it now stands for the ball."""
    moved = tip_moved(model, nominal)
    if moved <= TIP_MOVED:
        _warn_closer_end(model, nominal, tree, moved, source)
        return nominal
    tip = nominal.extras["urdf"]["tip_link"]
    ends = _ends_at(model, tree, base_link)
    end = ends[0] if len(ends) == 1 else None
    if end is not None and end != tip:
        warnings.warn(
            f"{source}: field 'tip_link': the calibration's tool point is {moved * 1e3:.0f} mm from {tip!r}, the "
            f"tip link it was calibrated with, and at {end!r} of this URDF: written at {end!r} ({tip!r} kept where "
            "this URDF has it)", stacklevel=3)
        return urdf_model(tree, end, base_link)
    warnings.warn(
        f"{source}: field 'tip_link': {tip!r} written at the calibrated tool point, {moved * 1e3:.0f} mm from its "
        "place in this URDF (the samples put the ball there: an adapter or sensor the URDF lacks); "
        f"{tip!r} of the written file is the ball, not the link it was: give the ball its own link (a fixed joint) "
        f"and calibrate with it as --tip-link to keep {tip!r} where it is", stacklevel=3)
    return nominal


def _warn_closer_end(model: RobotModel, nominal: RobotModel, tree: UrdfTree, moved: float, source: str) -> None:
    """Warn when a calibration's tool point, within :data:`TIP_MOVED` of its tip link (taken as the calibration's
    correction of it and written there), is nearer another end of the chain after the same joints by more than
    :data:`CLOSER_END`: the ball sat there, and --tip-link named a link millimetres from it (a review: a ball link
    6 mm from iiwa_link_ee, calibrated with the latter, moved it 7 mm onto the ball without a word; 10 mm further
    away the same mistake is found and written at the ball)."""
    links = nominal.extras["urdf"]
    base, tip = links["base_link"], links["tip_link"]
    movable = [j.name for j in tree.path(base, tip) if j.type in MOVABLE]
    frame = link_frames(nominal, np.zeros(nominal.n_joints))[-1]  # the last DH frame at q = 0, in the base link's
    poses = tree.world_poses(base)
    nearer = []
    for leaf, _ in tree.chain_ends(base):
        if leaf == tip or [j.name for j in tree.path(base, leaf) if j.type in MOVABLE] != movable:
            continue
        gap = float(np.linalg.norm(np.asarray(model.tool) - np.linalg.solve(frame, poses[leaf])[:3, 3]))
        if gap < moved - CLOSER_END:
            nearer.append((gap, leaf))
    if nearer:
        gap, leaf = min(nearer)
        warnings.warn(
            f"{source}: field 'tip_link': the calibration's tool point is {moved * 1e3:.1f} mm from {tip!r}, the tip "
            f"link it was calibrated with, and {gap * 1e3:.1f} mm from {leaf!r}, another end of this URDF: written at "
            f"{tip!r} as the calibration's correction of it (up to {TIP_MOVED * 1e3:.0f} mm is taken as one); if the "
            f"ball sat at {leaf!r}, calibrate again with --tip-link {leaf}", stacklevel=4)


def _refuse_new_tool(model: RobotModel, source: str, why: str) -> None:
    """Refuse, naming the new tool, a model whose tool ``spherecal tool`` replaced (its ``tool_swap`` block)
    when no link of the URDF is at it; return for any other model.

    Raises:
        ExportError: one line: where the tool is and how to give the URDF a link there.
    """
    if "tool_swap" not in model.extras:
        return
    tool = ", ".join(f"{v:.4f}" for v in model.tool)
    raise ExportError(
        f"{source}: field 'tip_link': the calibrated file carries a new tool (spherecal tool) at [{tool}] m in the "
        f"last frame and no link of this URDF is at it ({why}); add a link at the new tool (a fixed joint) and put "
        "the tool on with `spherecal tool --urdf` naming it with --tip-link, then export --into that URDF"
    )


def with_zeros_of(model: RobotModel, reference: RobotModel) -> RobotModel:
    """``model`` with ``reference``'s joint zeros (``theta_i``) when both describe their joints alike (convention,
    Hayati betas, geometric parameter names: a compliance or scale block beside them does not count, a review found
    an elastic Gen3 lite file with every compliance 0 refused where its dh twin was written); else ``model``."""
    if (model.convention, model.hayati, geometric_part(model).param_names) != (
            reference.convention, reference.hayati, geometric_part(reference).param_names):
        return model
    params = model.params.copy()
    params[model.layout.field("theta")] = reference.params[reference.layout.field("theta")]
    return model.with_params(params)


def _tool_point_gap(model: RobotModel, nominal: RobotModel) -> float:
    """Largest tool-point distance [m] between two arms after the best rigid fit (200 seeded configurations)."""
    q = model.random_configurations(200, np.random.default_rng(0))
    return float(registered_errors(tool_point(model, q), tool_point(nominal, q)).max())


def _matching_end(model: RobotModel, tree: UrdfTree, base_link: str | None) -> str | None:
    """For a model that names no tip link: the one end of the URDF's chain whose tool point is the model's
    (within :data:`SAME_ROBOT_TOL`; a gripper's fingers, a tool frame and a ball are ends far apart), or None
    (one end, none matching, or several: the default tip and its refusal then apply)."""
    base = tree.root if base_link is None else base_link
    if base not in tree.links or len(tree.chain_ends(base)) < 2:
        return None
    matching = _ends_at(model, tree, base_link)
    return matching[0] if len(matching) == 1 else None


def _ends_at(model: RobotModel, tree: UrdfTree, base_link: str | None) -> list[str]:
    """The ends of the URDF's chain whose tool point is the model's, within :data:`SAME_ROBOT_TOL`."""
    base = tree.root if base_link is None else base_link
    ends = [leaf for leaf, _ in tree.chain_ends(base)] if base in tree.links else []
    matching = []
    for leaf in ends:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", NearlyParallelAxesWarning)
                nominal = urdf_model(tree, leaf, base_link)
        except RobotFileError:
            continue
        if nominal.n_joints != model.n_joints:
            continue
        if _tool_point_gap(with_zeros_of(model, nominal), nominal) <= SAME_ROBOT_TOL:
            matching.append(leaf)
    return matching


def urdf_into(model: RobotModel, text: str, source: str = "<urdf>", header: str = "") -> str:
    """The user's URDF text with the joint origins of the calibrated chain (and of the fixed
    joint into the tip link) changed so that its forward kinematics is ``model``'s.

    Args:
        model: the calibrated robot; ``extras["urdf"]`` (from a URDF import) names the base and
            tip links, otherwise the URDF's root and the one end of its serial chain are used (of a chain
            that ends in several links, the one whose tool point is the model's).
        text: the original URDF document.
        source: its file name, for error messages.
        header: comment lines (inputs, versions) for the provenance comment.

    Raises:
        ExportError: a chain that does not match the model (joint count, names, geometry), or
            a tip link that is the child of the last revolute joint (nowhere to put the tool).
    """
    tree = parse_urdf(text, source)
    # a calibrated file naming a link this URDF lacks (a calibration of an embedded arm, or of another file of it):
    # its names are another description's, and this URDF's own chain is matched to the model, as for a file that
    # names none
    links = model.extras.get("urdf") or {}
    ours = all(name in tree.links for name in _named_chain(links))
    if not ours:
        links = {"tip_link": _end_of_another_description(model, tree, links, source)}
    with warnings.catch_warnings():  # the user was told about parallel axes when the model was imported
        warnings.simplefilter("ignore", NearlyParallelAxesWarning)
        tip_link = links.get("tip_link") or _matching_end(model, tree, links.get("base_link"))
        base_link = links.get("base_link") or tree.root
        if tip_link is None and base_link in tree.links and len(tree.chain_ends(base_link)) > 1:
            _refuse_new_tool(model, source, "none of its chain's ends is there")
        nominal = urdf_model(tree, tip_link, links.get("base_link"))
        nominal = _tip_at_the_ball(model, nominal, tree, links.get("base_link"), source)
    base, tip = nominal.extras["urdf"]["base_link"], nominal.extras["urdf"]["tip_link"]
    _check_same_arm(model, nominal, source, names=ours)
    calibrated = to_modified(model)
    joints = tree.path(base, tip)
    movable = [j for j in joints if j.type in MOVABLE]
    if joints[-1].type != "fixed":
        raise ExportError(f"{source}: tip link {tip!r} is the child of joint {joints[-1].name!r}: "
                          "a calibrated tool point needs a fixed joint into the tip link")
    zero = np.zeros(model.n_joints)
    dh_nominal, dh_calibrated = link_frames(nominal, zero)[1:], link_frames(calibrated, zero)[1:]
    poses = tree.world_poses(base)  # nominal link poses at q = 0, in the base link frame
    placed = {base: np.eye(4)}
    origins: dict[str, np.ndarray] = {}
    for joint in joints:
        parent = placed[joint.parent]
        if joint.type in MOVABLE:
            k = movable.index(joint)
            child = dh_calibrated[k] @ np.linalg.solve(dh_nominal[k], poses[joint.child])
            origins[joint.name] = np.linalg.solve(parent, child)
        elif joint is joints[-1]:
            # The tip: its nominal orientation in the last DH frame, its origin at the calibrated tool point.
            in_dh = np.linalg.solve(dh_nominal[-1], poses[tip])
            in_dh[:3, 3] = calibrated.tool
            child = dh_calibrated[-1] @ in_dh
            origins[joint.name] = np.linalg.solve(parent, child)
        else:
            child = parent @ joint.origin
        placed[joint.child] = child
    written = replace_origins(text, origins, source)
    # Self-check: the written file, read back as any URDF, is the calibrated model.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NearlyParallelAxesWarning)
        check = urdf_model(parse_urdf(written, source), tip, base)
    q = model.random_configurations(100, np.random.default_rng(1))
    error = np.abs(tool_point(check, q) - tool_point(model, q)).max()
    if error > 1e-9:
        raise ExportError(f"{source}: the calibrated model's DH frames do not follow this URDF's joints "
                          f"(written file off by {error * 1e3:.3g} mm)")
    start = _masked(written).find("<robot")
    prolog, stripped = _without_our_comments(written[:start])
    replaced = (f"\nthe comments of the earlier spherecal export that wrote {source} are replaced by these "
                "(its file and digest above)") if stripped else ""
    comment = xml_comment(f"joint origins of {', '.join(origins)} written by spherecal\n{header}{replaced}") + "\n"
    comment += provenance_comment(model) + "\n"
    return prolog + comment + written[start:]


def _without_our_comments(prolog: str) -> tuple[str, bool]:
    """The text before ``<robot>`` without the comments an earlier :func:`urdf_into` put there, and whether it held
    any. An export into a file a former export wrote describes the joint origins it writes, not those it replaces:
    the old comments stacked (a calibration's provenance block, 49 kB with its self-check, grew an iiwa14 URDF of
    5 kB to 55, 104, 153 kB over three exports into the last result). The user's own comments are kept."""
    kept = _OUR_COMMENTS.sub("", prolog)
    return kept, kept != prolog
