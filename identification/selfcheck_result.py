"""What the calibration self-check found: one :class:`Finding` per check, the :class:`SelfCheck` verdict,
and the refusal (:class:`InconsistentDataError`, one line)."""

from __future__ import annotations

import re
from collections.abc import Collection, Sequence
from dataclasses import dataclass, field
from statistics import median

from spherecal.correction.errors import SpherecalError


class CalibrationRefused(SpherecalError):
    """A calibration the data cannot support (:class:`InconsistentDataError`,
    :class:`.problem.ImplausibleCalibrationError`): printed as its reason, then its clauses (:attr:`lines`)."""

    @property
    def lines(self) -> tuple[str, ...]:
        """The refusal as the command line prints it (:func:`refusal_lines`): its reason in a first line, then its
        clauses (figures, causes, remedies, the commands to try) one a line; the message alone when it is short."""
        return refusal_lines(str(self))


@dataclass(frozen=True)
class Advice:
    """A refusal's advice to leave out fixture ``fixture`` (:func:`leave_out_advice`), kept apart from its text: the
    workflow tries it, and where leaving the fixture out does not help, the refusal says 'record it again' in its place
    (:meth:`InconsistentDataError.told`)."""

    fixture: str

    def __str__(self) -> str:
        return leave_out_advice(self.fixture)


#: A piece of a refusal's text: plain text, or the advice to leave a fixture out.
Piece = str | Advice


def told(pieces: Sequence[Piece], tried: Collection[str] = ()) -> str:
    """The text of ``pieces``; the advice to leave out a fixture of ``tried`` (the workflow tried it, and it did not
    help) reads 'record it again'."""
    return "".join("record it again" if isinstance(p, Advice) and p.fixture in tried else str(p) for p in pieces)


class InconsistentDataError(CalibrationRefused):
    """The samples, fixtures and declared noise contradict each other, or the result cannot beat nominal.

    Attributes:
        pieces: the message as it was composed (:data:`Piece`: text, and the advice to leave a fixture out apart).
        moved: fixtures the refusal names: whose residual trends with recording order (the socket or the ball moved
            while they were recorded), or the one fixture that alone explains the inconsistency (the culprit); the
            workflow says what leaving them out gives (:func:`.workflow.run_workflow`).
    """

    def __init__(self, message: str | Sequence[Piece], moved: tuple[str, ...] = ()) -> None:
        self.pieces = (message,) if isinstance(message, str) else tuple(message)
        super().__init__(told(self.pieces))
        self.moved = tuple(moved)

    def told(self, tried: Collection[str]) -> str:
        """The message with the advice to leave out a fixture of ``tried`` reading 'record it again' (:func:`told`)."""
        return told(self.pieces, tried)


#: A refusal longer than this [characters] is printed as a short first line and its clauses below it (a user trial:
#: MUKCa's dinova_2 gen3lite refused in one line of 1,850 characters).
HEADLINE = 160


def refusal_lines(message: str) -> tuple[str, ...]:
    """A long refusal (over :data:`HEADLINE` characters) as a first line saying it is refused and why, then each of its
    clauses (the message split at every '; ' outside parentheses) in order: every word of the message is in them.

    The first line is the first clause's location (file, rows, field: every refusal names them in its line) and its
    reason without what it says in parentheses and without what follows its first ': ' (the causes and figures that
    the clause's own line gives): ``refused: samples.csv: rows 7-30: residual noise 1.09 mm per axis with the prior's
    rows is 3.64x the fit's default noise 0.3 mm and no single fixture, distance or position explains it``.
    """
    if len(message) <= HEADLINE:
        return (message,)
    clauses = _split_outside_parentheses(message, "; ")
    first = clauses[0]
    located = _LOCATION.match(first)
    where, reason = (first[: located.end()], first[located.end():]) if located else ("", first)
    reason = _split_outside_parentheses(_without_parentheses(reason), ": ")[0].strip()
    return (f"refused: {where}{reason}", *clauses)


#: A finding's location: ``samples.csv: rows 7-30: ``, ``samples.csv: rows 7-26, field 'fixture': ``, ``samples: all
#: rows: `` (:func:`.problem.samples_location`), ``samples.csv: rows 2, 5, ..., field 'q*': ``, ``fixtures.yaml: field
#: 'distances[0]': ``.
_LOCATION = re.compile(r"^[^\n]*?: (?:(?:all rows|rows? \d[\d, .-]*?)(?:, field '[^']*')?|field '[^']*'): ")


def _split_outside_parentheses(text: str, separator: str) -> list[str]:
    """``text`` split at every ``separator`` outside parentheses (a figure's '(limit 2x; worst fixture ...)' stays)."""
    parts, depth, start, k = [], 0, 0, 0
    while k < len(text):
        char = text[k]
        depth += (char == "(") - (char == ")")
        if depth <= 0 and text.startswith(separator, k):
            parts.append(text[start:k])
            start = k = k + len(separator)
            continue
        k += 1
    return [*parts, text[start:]]


def _without_parentheses(text: str) -> str:
    """``text`` without its parenthesised groups (and the space before each)."""
    out, depth = [], 0
    for char in text:
        if char == "(":
            depth += 1
        if depth == 0:
            out.append(char)
        if char == ")" and depth:
            depth -= 1
    return re.sub(r" +(?=[ ,:;.]|$)", "", "".join(out))


#: A fixture whose residual per axis exceeds this multiple of the median of the other fixtures' stands out
#: (:meth:`SelfCheck._standing_out`): the residual level's own limit (its residual against the noise).
STANDS_OUT = 2.0


@dataclass(frozen=True)
class Finding:
    """One check.

    Attributes:
        check: what was checked (``"residual level"``, ``"distance P1-P2"``, ``"position P2"``,
            ``"fixture P3"``, ``"prediction"``, ``"separation P1-P2"``, ``"motion P2"``).
        passed: False when the check failed (True also for ``unchecked`` findings).
        message: one line for humans (the refusal's text when it failed), composed of the pieces below where the
            check has them.
        figures: plain numbers (mm where the key says so).
        culprit: a failure that names the one input to fix.
        clause: the part of ``message`` that a later message quotes, without the file it names and the verdict: a
            failed residual level's noise (its rows, the figure, a cause it names), a trend's move (the fixture, the
            move), the prediction's figures; "" for the other checks.
        remedy: what ``message`` says after ``clause``: a failed prediction's remedy, a failed residual level's list of
            what may cause it (what judging at the noise the residuals show answers); "" otherwise.
        notes: clauses ``message`` ends with after them (the prediction's: its residuals' serial correlation, the
            arm's joint-angle error).
    """

    check: str
    passed: bool
    message: str
    figures: dict = field(default_factory=dict)
    culprit: bool = False
    clause: str = ""
    remedy: str = ""
    notes: tuple[str, ...] = ()


@dataclass(frozen=True)
class SelfCheck:
    """Every finding of the self-check and the verdict.

    Attributes:
        findings: all checks, in the order they ran.
        noise: declared noise per coordinate [m].
        sigma: residual std per coordinate of the fit [m].
        prediction: the parameters' predicted error covariance at the noise judged with
            (``noise_m``, ``parameters``, ``covariance`` [m, rad squared]): what ``validate`` predicts
            held-out sockets' spreads with (:func:`.prediction.socket_spreads`).
        forced: an inconsistent calibration returned anyway (``calibrate(force=True)``, ``--force``): the summary
            says it is written because forced.
    """

    findings: tuple[Finding, ...]
    noise: float
    sigma: float
    prediction: dict = field(default_factory=dict)
    forced: bool = False

    @property
    def failed(self) -> tuple[Finding, ...]:
        return tuple(f for f in self.findings if not f.passed)

    @property
    def consistent(self) -> bool:
        return not self.failed

    @property
    def culprit(self) -> Finding | None:
        """The failed check that names the one input to fix, if there is one."""
        return next((f for f in self.failed if f.culprit), None)

    @property
    def refusal(self) -> str:
        """The one line of a refusal ("" when consistent): the culprit, else the failed level or
        prediction figure, else the most inconsistent group with the note that no single one explains it."""
        return told(self._refusal()[0])

    def _refusal(self) -> tuple[tuple[Piece, ...], tuple[str, ...]]:
        """(:attr:`refusal` as :data:`Piece` s, the fixtures it names for leaving out: a culprit fixture, a trending
        one, and on a refusal of the residual level the fixture that stands out before the trending ones)."""
        failed = self.failed
        if not failed:
            return (), ()
        if self.culprit is not None:
            text, moved = self._with_trend(self.culprit)
            if not moved and self.culprit.check.startswith("fixture "):  # left out even without a trend
                moved = (self.culprit.check.removeprefix("fixture "),)
            return text, moved
        figures = [f for f in failed if f.check in ("residual level", "prediction")]
        if figures:
            # a model that does not describe the arm moves every residual: its trends are no moved socket to leave out
            alien = figures[0].figures.get("not_a_socket", False)
            trends = [] if alien else sorted((f for f in self.findings if f.figures.get("trend")),
                                             key=lambda f: -f.figures.get("change_mm", 0.0))  # strongest first
            moved = () if self._one_fixture else tuple(_fixture_of(f) for f in trends)
            standing = None if alien else self._standing_out()
            if standing is not None and standing not in moved:  # tried first: the level names it as the worst
                moved = (standing, *moved)
            text: tuple[Piece, ...] = (figures[0].message,)
            for trend in trends:
                text += ("; ", *_trend_told(trend, self._one_fixture))
            return text, moved
        worst = max(failed, key=lambda f: f.figures.get("statistic", 0.0) - f.figures.get("dof", 0))
        others = len(failed) - 1
        text, moved = self._with_trend(worst)
        if not others:
            return text, moved
        return (*text, f"; {others} other check(s) failed too and no single one explains the data"), moved

    def _standing_out(self) -> str | None:
        """The fixture whose residual per axis exceeds :data:`STANDS_OUT` x the median of the others' (the residual
        level's ``per_fixture_std_mm``), if one does: a refusal on the residual level names it as the worst fixture,
        and leaving it out is tried before the trending ones (a review: MUKCa's dinova_2 with a 2 deg offset on half of
        one socket's presses, worst fixture at 4.46 mm among 1-1.5, was refused naming two other sockets' real
        trends, and leaving those out did not help; leaving the worst one out wrote the rest)."""
        level = next((f for f in self.findings if f.check == "residual level"), None)
        per = level.figures.get("per_fixture_std_mm", {}) if level is not None else {}
        if len(per) < 3:  # beside one other fixture, which of the two stands out is no evidence
            return None
        worst = max(per, key=per.get)
        return worst if per[worst] > STANDS_OUT * median(v for k, v in per.items() if k != worst) else None

    def _with_trend(self, finding: Finding) -> tuple[tuple[Piece, ...], tuple[str, ...]]:
        """A fixture's failed ``finding`` (as :data:`Piece` s) with the trend of the same fixture, if its residual
        trends with recording order (then the fixture is the one to leave out), and that fixture."""
        trend = next((f for f in self.findings if f.figures.get("trend") and finding.check.endswith(
            " " + _fixture_of(f))), None)
        if trend is None:
            return (finding.message,), ()
        return ((finding.message, "; ", *_trend_told(trend, self._one_fixture)),
                () if self._one_fixture else (_fixture_of(trend),))

    @property
    def _one_fixture(self) -> bool:
        """The recording has one fixture (the residual level's per-fixture figures): nothing to leave out."""
        level = next((f for f in self.findings if f.check == "residual level"), None)
        return level is not None and len(level.figures.get("per_fixture_std_mm", {})) == 1

    def raise_if_inconsistent(self) -> None:
        """Raises :class:`InconsistentDataError` with :attr:`refusal` (and the fixtures it advises leaving out)
        unless consistent."""
        if not self.consistent:
            raise InconsistentDataError(*self._refusal())

    @property
    def warnings(self) -> tuple[str, ...]:
        """Passed checks the user must still know of: a fixture whose residual trends with recording
        order, residuals above the declared noise judged at the noise they show, a calibration not expected to beat
        nominal far from the recording."""
        found = [trend_text(f, self.consistent, self._one_fixture) if f.figures.get("trend") else f.message
                 for f in self.findings
                 if f.figures.get("trend") or f.figures.get("honest_noise_warning")]
        return tuple(found + [f.figures["region_warning"] for f in self.findings
                              if isinstance(f.figures.get("region_warning"), str)])

    def block(self) -> dict:
        """Plain data for the ``calibration:`` block of the written file."""
        return {
            "verdict": "consistent" if self.consistent else "inconsistent",
            "noise_assumed_mm": self.noise * 1e3,  # declared (--noise) or the default: options.noise_declared says
            "residual_std_mm": self.sigma * 1e3,
            "failed": [f.message for f in self.failed],
            "warnings": list(self.warnings),
            "checks": {f.check: {"passed": f.passed, **f.figures} for f in self.findings},
            **({"prediction": self.prediction} if self.prediction else {}),
        }

    def lines(self) -> list[str]:
        """A few lines for the printed summary."""
        head = (f"consistent{', with warnings' if self.warnings else ''}" if self.consistent
                else f"INCONSISTENT ({len(self.failed)} failed)")  # warnings: the lines below that say 'warning'
        if self.forced and not self.consistent:  # not because it passed (a review: a forced run's level said 'written')
            head += ": written only because forced (--force)"
        lines = [f"self-check: {head}"]
        lines += [line for f in self.findings if f.check in ("residual level", "prediction") and f.passed
                  for line in _clauses(f.message)]
        lines += [line for f in self.findings if f.figures.get("trend")
                  for line in _clauses(trend_text(f, self.consistent, self._one_fixture))]
        worst = _worst_group(self.findings)
        if worst is not None:
            figures = worst.figures
            size = (
                f"{figures['disagreement_mm']:.3g} mm"
                if "disagreement_mm" in figures
                else (f"{figures.get('disagreement_rms_mm', 0.0):.3g} mm rms")
            )
            lines.append(
                f"  closest to failing when left out: {worst.check}, {size} from what the rest predicts "
                f"(p = {_p_value(figures['log10_p'])}, {figures['excess']:.2g} std per row)"
            )
        lines += [f"  unchecked: {f.message}" for f in self.findings if f.figures.get("unchecked")]
        # a review: a forced Gen3 lite's failed prediction was one summary line of 1,500 characters
        shown: list[Finding] = []
        for f in self.failed:
            lines += _clauses(f"FAILED: {_once(f, shown)}")
            shown.append(f)
        return lines


def _once(finding: Finding, shown: list[Finding]) -> str:
    """A failed ``finding``'s message for the summary, without the figures a failure printed above it already quotes
    (its :attr:`Finding.clause`) and without the clauses that one printed: its verdict, where those figures are, and
    what else it says. A review: a forced one-socket Gen3 lite (MUKCa's dinova_2 gen3lite) printed the prediction's
    figures twice, under its failed residual level (which quotes them) and under its failed prediction."""
    message, clause = finding.message, finding.clause
    quoting = next((g for g in shown if clause and clause in g.message), None)
    start = message.find(clause) if quoting is not None else -1
    verdict = message[:max(start, 0)].rstrip(": ")
    if not verdict:
        return message
    printed = set(_split_outside_parentheses(quoting.message, "; "))
    rest = [c for c in _split_outside_parentheses(message[start + len(clause):], "; ") if c and c not in printed]
    return "; ".join([f"{verdict} (its figures above, under the failed {quoting.check})", *rest])


def _p_value(log10_p: float) -> str:
    """A p-value from its log10: plain down to 0.001 (``0.63``; a review read ``p = 10^-0.0`` and ``10^-0.2`` in a
    real arm's summary), a power of ten below it (``10^-9.3``)."""
    return f"{10.0 ** log10_p:.2g}" if log10_p >= -3.0 else f"10^{log10_p:.1f}"


def _clauses(message: str) -> list[str]:
    """A finding's message as summary lines: indented, and over :data:`HEADLINE` characters its clauses (split at
    every '; ' outside parentheses) one a line, the later ones indented once more. A h8 trial: a written Gen3 lite's
    prediction was one line of about 1,000 characters, its 'warning: over the whole workspace ...' in the middle."""
    if len(message) <= HEADLINE:
        return [f"  {message}"]
    first, *rest = _split_outside_parentheses(message, "; ")
    return [f"  {first}", *(f"    {clause}" for clause in rest)]


#: The advice for a fixture that moved or whose samples stray, when it is the recording's only fixture: record it again,
#: never leave it out (that leaves nothing to calibrate). One phrase for a refusal's trend (:func:`_trend_advice`), a
#: written file's trend warning (:func:`trend_text`) and a robust loss's discount warning
#: (:func:`.calibrate._discounted_socket`), which read 'record it again (it is the only fixture)', 'it is the only
#: fixture, so it is kept (record it again to check it)' and 'it is the only fixture: record it again' (a review).
ONLY_FIXTURE = "record it again (it is the only fixture)"


def trend_text(finding: Finding, kept: bool, only: bool = False) -> str:
    """A trend finding's message (a fixture whose residual trends with recording order) with what it means and what
    to do: in a refusal, leave the fixture out or record it again; in a written calibration (``kept``), the checks
    found the fixture consistent with the rest ('the other fixtures' read oddly beside one other) and it was kept, and
    how to leave it out (``only``: the recording's one fixture, to record again (:data:`ONLY_FIXTURE`), not to leave
    out, in a refusal, a written file's warning and a forced file's summary alike, a written one's to tell a moved
    socket from the arm's own error; a review: a forced one-socket calibration, MUKCa's dinova_1 ``front_h0``, printed
    'leave it out (calibrate --exclude-fixture front_h0)' under its summary). A written file's warning does not advise
    leaving it out: on every real Gen3 lite recording written with a trending socket, the calibration with the socket
    beat the one without it at sockets it never saw (stop 10), and leaving out MUKCa's dinova_2 ``front_rotated_h1``
    leaves one socket, which is refused."""
    name = _fixture_of(finding)
    if kept:
        kept_because = (f"the checks pass, so it is kept; to tell which, {ONLY_FIXTURE}" if only else
                        f"the checks find it consistent with the rest, so it is kept (calibrate "
                        f"--exclude-fixture {name} leaves it out)")
        return (f"{finding.message}: the socket or the ball moved while it was recorded, or the arm's own error "
                f"changes along the self-motion; {kept_because}")
    return finding.message + told(_trend_advice(finding, only))


def _trend_told(finding: Finding, only: bool) -> tuple[Piece, ...]:
    """A trend in a refusal, joined after the finding that says where: the move (its :attr:`Finding.clause`, without
    the file and rows) with what it means and what to do (:func:`trend_text`)."""
    return (finding.clause, *_trend_advice(finding, only))


def _trend_advice(finding: Finding, only: bool) -> tuple[Piece, ...]:
    """What a refused trend means and what to do, after its move: leave the fixture out (:class:`Advice`) or record it
    again; ``only`` (a review: a one-socket refusal advised leaving out the only socket): record it again."""
    moved = ": the socket or the ball moved while it was recorded; "
    return (f"{moved}{ONLY_FIXTURE}",) if only else (moved, Advice(_fixture_of(finding)))


def leave_out_advice(name: str) -> str:
    """The advice of a refusal that names fixture ``name``: ``leave it out (calibrate --exclude-fixture NAME) or record
    it again`` (:func:`.workflow.run_workflow` tries it, and keeps only 'record it again' when it does not help)."""
    return f"leave it out (calibrate --exclude-fixture {name}) or record it again"


def _fixture_of(trend: Finding) -> str:
    """The fixture a trend finding (check ``"trend NAME"``) is about."""
    return trend.check.removeprefix("trend ")


def _worst_group(findings: tuple[Finding, ...]) -> Finding | None:
    groups = [f for f in findings if "log10_p" in f.figures and f.passed and not f.figures.get("unchecked")]
    return min(groups, key=lambda f: f.figures["log10_p"]) if groups else None
