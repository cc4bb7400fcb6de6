"""Reading a URDF: the tree of links and joints, the revolute chain between two links.

Only kinematics (and, when present, ``<inertial>``) is read: ``<visual>`` and ``<collision>``
are ignored, so a URDF whose mesh files are not shipped is still a valid robot description.
Every pose is evaluated at the URDF's zero configuration (all joint values 0).
"""

from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from xml.parsers import expat

import numpy as np

from ..inertia import FIELDS, rotated, tensor
from ..model import pose_matrix
from .robot_file import MAX_ANGLE, MAX_LENGTH, RobotFileError
from .suggest import close_names
from .text_input import plain_float, read_xml_text

MOVABLE = ("revolute", "continuous")
KNOWN_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")
#: Most ``<link>`` (and so ``<joint>``) elements read: a robot arm has tens (a humanoid with hands about
#: 100); counted before any traversal, so that a huge or generated file is refused at once.
MAX_LINKS = 2000
#: Most movable joints on the calibrated chain (a serial arm has 6-7; a 64-joint chain is no arm, and its
#: calibration problem would be thousands of columns wide).
MAX_CHAIN_JOINTS = 64
#: Chain ends closer than this [m] are one tool point (a flange and its ``tool0`` frame): no choice to make.
SAME_POINT_TOL = 1e-6
#: Most chain ends a refusal lists.
MAX_LISTED = 8
#: The xacro namespace: an element in it is a macro not yet expanded.
XACRO_NAMESPACE = "{http://www.ros.org/wiki/xacro}"
#: How to expand a xacro file (for refusals).
EXPAND = "a .xacro file, not yet a URDF: expand it first (xacro robot.urdf.xacro > robot.urdf)"


@dataclass(frozen=True)
class UrdfJoint:
    """One ``<joint>``: its origin (4, 4) in the parent link frame [m], unit axis (3,)."""

    name: str
    type: str
    parent: str
    child: str
    origin: np.ndarray
    axis: np.ndarray
    lower: float | None = None
    upper: float | None = None
    mimic: str | None = None
    row: int | None = None  # the file line of the <joint> element (for messages)
    effort: float | None = None  # <limit effort> [N m] of a revolute or continuous joint, None when absent or 0
    velocity: float | None = None  # <limit velocity> [rad/s], likewise


@dataclass(frozen=True)
class Inertial:
    """A link's mass [kg], centre of mass (3,) in the link frame [m] and its (3, 3) inertia tensor about the centre
    of mass in the link frame's axes [kg m^2] (the ``<inertia>`` turned by the ``<origin rpy>``; None without an
    ``<inertia>`` element)."""

    mass: float
    com: np.ndarray
    inertia: np.ndarray | None = None


@dataclass(frozen=True)
class UrdfTree:
    """A parsed URDF: links, joints by child link, the root link."""

    source: str
    name: str
    links: tuple[str, ...]
    joints: dict[str, UrdfJoint]  # by child link name
    root: str
    inertials: dict[str, Inertial] = field(default_factory=dict)

    def children(self, link: str) -> list[UrdfJoint]:
        """Joints whose parent is ``link``, in file order."""
        return [j for j in self.joints.values() if j.parent == link]

    def path(self, base: str, tip: str) -> list[UrdfJoint] | None:
        """Joints from ``base`` down to ``tip`` (None when ``tip`` is not below ``base``)."""
        joints: list[UrdfJoint] = []
        link = tip
        while link != base:
            joint = self.joints.get(link)
            if joint is None or len(joints) > len(self.joints):  # bounded: a loop never ends at the base
                return None
            joints.append(joint)
            link = joint.parent
        return joints[::-1]

    def world_poses(self, base: str) -> dict[str, np.ndarray]:
        """(4, 4) pose of every link below ``base`` (``base`` included) in ``base``'s frame, q = 0."""
        poses = {base: np.eye(4)}
        stack = [base]
        while stack:
            link = stack.pop()
            for joint in self.children(link):
                poses[joint.child] = poses[link] @ joint.origin
                stack.append(joint.child)
        return poses

    def chain_ends(self, base: str) -> list[tuple[str, str]]:
        """Where the serial chain below ``base`` can end: ``(leaf link, child link of the last revolute joint
        above it)`` in file order, depth first.

        The chain goes down through revolute and continuous joints; its ends are the leaf links below the last
        of them reached through fixed joints only (below a prismatic finger or a coupled ``<mimic>`` joint is
        no end: a gripper's moving part; such a joint with revolute joints after it stays on the chain, for
        :func:`chain` to refuse).
        """
        ends: list[tuple[str, str]] = []
        # (link, child link of the last revolute joint above it, a moving tool joint since that one)
        stack: list[tuple[str, str | None, bool]] = [(base, None, False)]
        while stack:  # the tree is loop-free (checked by parse_urdf)
            link, flange, moving = stack.pop(0)
            below = self.children(link)
            if not below and flange is not None and not moving:
                ends.append((link, flange))
            stack[:0] = [(j.child, j.child, False) if j.type in MOVABLE and j.mimic is None
                         else (j.child, flange, moving or j.type != "fixed") for j in below]
        return ends

    def default_tip(self, base: str) -> str:
        """The tool link when none is named: the one end of the serial chain below ``base``
        (:meth:`chain_ends`). With one end, or several at the same point (a flange and a ``tool0`` frame), the
        first in file order; with ends at different points (a gripper's fingers beside a ball or a tool frame)
        the choice is the user's.

        Raises:
            RobotFileError: ends at different points, each listed with its distance [mm] from the frame of
                the last movable joint before it (one line).
        """
        ends = self.chain_ends(base)
        if not ends:
            return base  # no movable joint below: chain() names the problem
        poses = self.world_poses(base)
        points = np.array([poses[leaf][:3, 3] for leaf, _ in ends])
        if np.ptp(points, axis=0).max() <= SAME_POINT_TOL:
            return ends[0][0]
        listed = ", ".join(
            f"{leaf} ({np.linalg.norm(poses[leaf][:3, 3] - poses[flange][:3, 3]) * 1e3:.0f} mm from {flange})"
            for leaf, flange in ends[:MAX_LISTED])
        more = f" and {len(ends) - MAX_LISTED} more" if len(ends) > MAX_LISTED else ""
        raise RobotFileError(
            f"{self.source}: the chain below {base!r} ends in {len(ends)} links at different points: "
            f"{listed}{more}; name the tool's link with --tip-link (for calibrate and import, the link at the ball's "
            "centre; for tool, the new tool's point)"
        )


def _floats(text: str | None, count: int, default: list[float], where: str) -> list[float]:
    if text is None:
        return default
    if "${" in text or "$(" in text:
        raise RobotFileError(f"{where}: {text!r} holds an unexpanded xacro expression ({EXPAND})")
    parts = text.split()
    try:
        values = [plain_float(v) for v in parts]
    except ValueError:
        raise RobotFileError(f"{where}: expected {count} numbers, got {text!r}") from None
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise RobotFileError(f"{where}: expected {count} finite numbers, got {text!r}")
    return values


@dataclass(frozen=True)
class _Rows:
    """The file line of each element of a parsed URDF, for messages ``FILE: row N, field 'F': ...``."""

    source: str
    lines: dict[ET.Element, int]

    def at(self, element: ET.Element | None, field: str) -> str:
        """The message prefix of ``field`` (``joint panda_joint2 <origin rpy>``) at ``element``'s row."""
        row = self.lines.get(element) if element is not None else None
        return f"{self.source}: {'' if row is None else f'row {row}, '}field '{field}'"


def _xml_tree(text: str, source: str) -> tuple[ET.Element, dict[ET.Element, int]]:
    """The element tree of XML ``text`` and the file line where each element starts.

    The stdlib's expat parser, as ``ET.fromstring`` uses it (internal entities expanded within expat's
    amplification limits, external entities never fetched), with its line numbers kept.

    Raises:
        RobotFileError: invalid XML (one line naming the row).
    """
    builder = ET.TreeBuilder()
    parser = expat.ParserCreate(namespace_separator="}")
    parser.buffer_text = True
    lines: dict[ET.Element, int] = {}

    def fixed(name: str) -> str:  # expat's 'uri}tag' to ElementTree's '{uri}tag'
        return "{" + name if "}" in name else name

    def start(tag: str, attributes: dict[str, str]) -> None:
        element = builder.start(fixed(tag), {fixed(k): v for k, v in attributes.items()})
        lines[element] = parser.CurrentLineNumber

    parser.StartElementHandler = start
    parser.EndElementHandler = lambda tag: builder.end(fixed(tag))
    parser.CharacterDataHandler = builder.data
    try:
        parser.Parse(text, True)
    except expat.ExpatError as error:
        raise RobotFileError(f"{source}: row {error.lineno}: invalid XML: {error}") from None
    return builder.close(), lines


def _origin(element: ET.Element | None, rows: _Rows, field: str) -> np.ndarray:
    """(4, 4) of an ``<origin xyz rpy>`` (identity when absent); ``field`` names its owner (``joint j1``)."""
    if element is None:
        return np.eye(4)
    xyz = _floats(element.get("xyz"), 3, [0.0] * 3, rows.at(element, f"{field} <origin xyz>"))
    rpy = _floats(element.get("rpy"), 3, [0.0] * 3, rows.at(element, f"{field} <origin rpy>"))
    if max(abs(v) for v in xyz) > MAX_LENGTH:  # millimetres; the DH conversion would make it 1e18 m elsewhere
        raise RobotFileError(f"{rows.at(element, f'{field} <origin xyz>')}: {element.get('xyz')!r} is not physical "
                             f"(at most {MAX_LENGTH:g} m in magnitude; a URDF is in metres)")
    return pose_matrix(np.array(xyz), np.array(rpy))


def _name(element: ET.Element, rows: _Rows) -> str:
    name = element.get("name")
    if not name:
        raise RobotFileError(f"{rows.at(element, f'<{element.tag}>')}: <{element.tag}> without a name")
    return name


def _link_ref(joint: ET.Element, tag: str, rows: _Rows, field: str) -> str:
    ref = joint.find(tag)
    if ref is None or not ref.get("link"):
        raise RobotFileError(f"{rows.at(joint if ref is None else ref, field)}: missing <{tag} link=...>")
    return ref.get("link")


def _joint(element: ET.Element, rows: _Rows) -> UrdfJoint:
    name = _name(element, rows)
    field_name = f"joint {name}"
    where = rows.at(element, field_name)
    kind = element.get("type")
    if kind not in KNOWN_TYPES:
        raise RobotFileError(f"{where}: unknown type {kind!r} (expected one of {', '.join(KNOWN_TYPES)})")
    axis_element = element.find("axis")
    axis = np.array(_floats(axis_element.get("xyz") if axis_element is not None else None, 3, [1.0, 0.0, 0.0],
                            rows.at(axis_element, f"{field_name} <axis xyz>")))
    lower = upper = None
    if kind in ("revolute", "prismatic"):
        norm = float(np.linalg.norm(axis))
        if norm < 1e-12:
            raise RobotFileError(f"{rows.at(axis_element, f'{field_name} <axis xyz>')}: <axis xyz> is the zero vector")
        axis = axis / norm
    if kind == "revolute":
        limit = element.find("limit")
        if limit is None:
            raise RobotFileError(f"{where}: a revolute joint needs <limit lower upper>")
        lower, upper = (_floats(limit.get(k, "0"), 1, [0.0], rows.at(limit, f"{field_name} <limit {k}>"))[0]
                        for k in ("lower", "upper"))
        where = rows.at(limit, f"{field_name} <limit>")
        for key, value in (("lower", lower), ("upper", upper)):
            if abs(value) > MAX_ANGLE:
                raise RobotFileError(f"{rows.at(limit, f'{field_name} <limit {key}>')}: {value:g} rad is not physical "
                                     f"(at most {MAX_ANGLE:.6g} "
                                     "rad in magnitude; a URDF is in radians, not degrees)")
        if lower > upper:
            raise RobotFileError(f"{where}: <limit> lower ({lower}) > upper ({upper})")
        if lower == upper:  # URDF's defaults are 0: a <limit effort velocity/> gives a joint that cannot turn
            raise RobotFileError(f"{where}: <limit> lower and upper are both {lower:g} (missing from it?): a revolute "
                                 "joint needs its range [rad]")
    effort = velocity = None
    limit = element.find("limit")
    if kind in ("revolute", "continuous") and limit is not None:  # kept for a standalone export of a non-Franka arm
        effort, velocity = (_floats(limit.get(k), 1, [0.0], rows.at(limit, f"{field_name} <limit {k}>"))[0]
                            for k in ("effort", "velocity"))
        effort, velocity = (v if v > 0 else None for v in (effort, velocity))  # URDF's default is 0: none given
    mimic = element.find("mimic")
    if mimic is not None and not mimic.get("joint"):
        raise RobotFileError(f"{rows.at(mimic, f'{field_name} <mimic>')}: <mimic> without a joint=...")
    return UrdfJoint(name, kind, _link_ref(element, "parent", rows, f"{field_name} <parent>"),
                     _link_ref(element, "child", rows, f"{field_name} <child>"),
                     _origin(element.find("origin"), rows, field_name), axis, lower, upper,
                     None if mimic is None else mimic.get("joint"), rows.lines.get(element), effort, velocity)


def _inertial(link: ET.Element, name: str, rows: _Rows) -> Inertial | None:
    element = link.find("inertial")
    if element is None:
        return None
    field_name = f"link {name} <inertial>"
    mass_element = element.find("mass")
    where = rows.at(element if mass_element is None else mass_element, f"{field_name} <mass>")
    mass = _floats(mass_element.get("value") if mass_element is not None else None, 1, [0.0], where)[0]
    if mass < 0.0:
        raise RobotFileError(f"{where}: negative mass {mass}")
    origin = _origin(element.find("origin"), rows, field_name)
    inertia_element = element.find("inertia")
    inertia = None
    if inertia_element is not None:  # read as given (rounded published tensors may break the triangle inequality)
        where = rows.at(inertia_element, f"{field_name} <inertia>")
        six = [_floats(inertia_element.get(key), 1, [0.0], f"{where} {key}")[0] for key in FIELDS]
        inertia = rotated(tensor(np.array(six)), origin[:3, :3])
    return Inertial(mass, origin[:3, 3], inertia)


def parse_urdf(text: str, source: str = "<urdf>") -> UrdfTree:
    """Parse URDF text into a tree.

    Raises:
        RobotFileError: invalid XML, a joint naming an unknown link, a link with two parents,
            a loop, several roots (one line naming ``source`` and the element).
    """
    root, lines = _xml_tree(text, source)
    rows = _Rows(source, lines)
    if root.tag != "robot":
        raise RobotFileError(f"{rows.at(root, f'<{root.tag}>')}: expected a <robot> root element, got <{root.tag}>")
    macro = next((e for e in root.iter() if isinstance(e.tag, str) and e.tag.startswith(XACRO_NAMESPACE)), None)
    if macro is not None:  # an include or a macro call brings links and joints this file does not hold
        tag = f"<xacro:{macro.tag[len(XACRO_NAMESPACE):]}>"
        raise RobotFileError(f"{rows.at(macro, tag)}: {tag} element: {EXPAND}")
    for tag in ("link", "joint"):  # bounded work: counted before anything is built or walked
        count = sum(1 for _ in root.iterfind(tag))
        if count > MAX_LINKS:
            raise RobotFileError(f"{rows.at(root, f'<{tag}>')}: {count} <{tag}> elements, at most {MAX_LINKS} are "
                                 "read (not a robot arm)")
    links: list[str] = []
    inertials: dict[str, Inertial] = {}
    for element in root.findall("link"):
        name = _name(element, rows)
        if name in links:
            raise RobotFileError(f"{rows.at(element, f'link {name}')}: link {name!r} is defined twice")
        links.append(name)
        inertial = _inertial(element, name, rows)
        if inertial is not None:
            inertials[name] = inertial
    if not links:
        raise RobotFileError(f"{rows.at(root, '<link>')}: no <link> elements")
    joints: dict[str, UrdfJoint] = {}
    names: set[str] = set()
    for element in root.findall("joint"):
        joint = _joint(element, rows)
        where = rows.at(element, f"joint {joint.name}")
        if joint.name in names:
            raise RobotFileError(f"{where}: joint {joint.name!r} is defined twice")
        names.add(joint.name)
        for role, link in (("parent", joint.parent), ("child", joint.child)):
            if link not in links:
                raise RobotFileError(f"{rows.at(element.find(role), f'joint {joint.name} <{role}>')}: {role} link "
                                     f"{link!r} is not defined")
        if joint.child in joints:
            raise RobotFileError(
                f"{where}: link {joint.child!r} has two parents "
                f"({joints[joint.child].parent!r} and {joint.parent!r}): loops are not supported"
            )
        joints[joint.child] = joint
    roots = [link for link in links if link not in joints]
    if len(roots) != 1:
        if not roots:
            raise RobotFileError(f"{rows.at(root, '<joint>')}: every link has a parent: the joints form a loop")
        second = root.findall("link")[links.index(roots[1])]
        raise RobotFileError(f"{rows.at(second, f'link {roots[1]}')}: several root links "
                             f"({', '.join(map(repr, roots))}): not one tree")
    tree = UrdfTree(source, root.get("name", ""), tuple(links), joints, roots[0], inertials)
    children: dict[str, list[str]] = {}
    for joint in joints.values():
        children.setdefault(joint.parent, []).append(joint.child)
    reached, stack = {roots[0]}, [roots[0]]
    while stack:  # one visit per link: linear, whatever the shape
        for child in children.get(stack.pop(), []):
            if child not in reached:
                reached.add(child)
                stack.append(child)
    for link, element in zip(links, root.findall("link"), strict=True):  # a cycle detached from the root
        if link not in reached:
            raise RobotFileError(f"{rows.at(element, f'link {link}')}: link {link!r} is not connected to the root "
                                 f"{roots[0]!r}: a loop")
    return tree


def read_urdf(path: str | os.PathLike) -> UrdfTree:
    """Read and parse a URDF file (see :func:`parse_urdf`), decoded in the encoding it declares (UTF-8 without
    a declaration)."""
    return parse_urdf(read_xml_text(path, RobotFileError), str(path))


def _joint_at(source: str, joint: UrdfJoint, part: str = "") -> str:
    """The message prefix ``FILE: row N, field 'joint NAME<part>'`` of a parsed joint."""
    return f"{source}: {'' if joint.row is None else f'row {joint.row}, '}field 'joint {joint.name}{part}'"


def _links_hint(tree: UrdfTree, link: str) -> str:
    """What a user who mistyped ``link`` needs (a user trial had to open the URDF): the names closest to it, and the
    ends of the tree (links no joint hangs from), a few of each."""
    parents = {joint.parent for joint in tree.joints.values()}
    ends = [name for name in tree.links if name not in parents]
    close = close_names(link, tree.links, cutoff=0.5, n=3)
    said = f" (did you mean {', '.join(map(repr, close))}?" if close else " ("
    shown = ", ".join(ends[:8]) + (f" and {len(ends) - 8} more" if len(ends) > 8 else "")
    return f"{said}{' ' if close else ''}its ends: {shown})"


def chain(
    tree: UrdfTree, base_link: str | None = None, tip_link: str | None = None
) -> tuple[str, str, list[UrdfJoint]]:
    """The joints from ``base_link`` (default: the root) to ``tip_link`` (default: the one end of
    the serial chain below the base, :meth:`UrdfTree.default_tip`).

    Returns:
        ``(base, tip, joints)``: every joint on the path, fixed ones included.

    Raises:
        RobotFileError: an unknown link (named by its option, ``field '--tip-link': no link 'x' in robot ...``,
            with the nearest names), a tip not below the base, a prismatic (or floating,
            planar) joint on the path, no revolute joint at all, or no ``tip_link`` where the chain
            ends in several links at different points.
    """
    source = tree.source
    base = tree.root if base_link is None else base_link
    for option, link in (("--base-link", base), ("--tip-link", tip_link)):  # the options that give them
        if link is not None and link not in tree.links:
            raise RobotFileError(f"{source}: field '{option}': no link {link!r} in robot {tree.name!r}"
                                 f"{_links_hint(tree, link)}")
    tip = tree.default_tip(base) if tip_link is None else tip_link
    joints = tree.path(base, tip)
    if joints is None:
        raise RobotFileError(f"{source}: tip link {tip!r} is not below base link {base!r}")
    for joint in joints:
        if joint.type not in MOVABLE + ("fixed",):
            raise RobotFileError(
                f"{_joint_at(source, joint)}: a {joint.type} joint between {base!r} and {tip!r} "
                "(only revolute, continuous and fixed joints can be calibrated)"
            )
    movable = sum(j.type in MOVABLE for j in joints)
    if not movable:
        raise RobotFileError(f"{source}: no revolute joint between {base!r} and {tip!r}")
    if movable > MAX_CHAIN_JOINTS:
        raise RobotFileError(
            f"{source}: {movable} revolute joints between {base!r} and {tip!r}, at most {MAX_CHAIN_JOINTS} "
            "(not a serial arm: choose --base-link and --tip-link)"
        )
    for joint in joints:
        if joint.mimic is not None and joint.type in MOVABLE:
            raise RobotFileError(
                f"{_joint_at(source, joint, ' <mimic>')}: it follows joint {joint.mimic!r} between {base!r} "
                f"and {tip!r}; a coupled joint cannot be calibrated as an independent one (choose --tip-link "
                "before it, or describe the chain without the coupling)"
            )
    return base, tip, joints
