"""The one predictor-corrector loop of hbm/: :func:`follow`.

From the problem's first point, each step: the limits (points, solves);
the direction (the secant, or the tangent, in the problem's metric); the
predictor and corrector (a plane normal to the direction at ``ds`` ahead
in arc-length steps, a solve at the next parameter in natural steps, see
:class:`~workbench.hbm.path.step.StepRule` for the modes); where the plane
fails, a sphere and a reversed plane (``fallbacks``); halving on failure
and on a refused step (too sharp a turn, too large a correction or
change, backwards, back onto a point already solved); the end of the
range (a point exactly there); the stops (turned back below the start,
folds); the point recorded by the problem (a lost contact ends the path,
or halves the step that found it, ``close_in``); the step grown from the
Newton iterations. What ends the loop is a :class:`Stop` (the problem's
words) or a numerical error; the points so far are kept either way.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from .problem import LostContact, PathProblem, Solution, Stop
from .step import StepRule

log = logging.getLogger(__name__)

NUMERICAL = (np.linalg.LinAlgError, FloatingPointError, ArithmeticError, RuntimeError)


@dataclass
class Outcome:
    completed: bool
    failed: bool
    message: str


def norm(v: np.ndarray, m: np.ndarray) -> float:
    """The length of ``v`` in the metric ``m``."""
    return float(np.sqrt(np.sum((m * v) ** 2)))


def follow(pb: PathProblem, rule: StepRule) -> Outcome:
    """Follow ``pb`` by ``rule`` from its first point; never raises for a failed solve."""
    try:
        completed = _loop(pb, rule)
        return Outcome(completed, False, "")
    except Stop as stop:
        (log.warning if stop.failed else log.info)("%s", stop)
        return Outcome(stop.completed, stop.failed, str(stop))
    except NUMERICAL as e:
        # a numerical breakdown inside the loop: report it, keep the points so far
        log.debug("path stopped", exc_info=True)
        message = pb.say("numerical", error=e)
        log.warning("%s", message)
        return Outcome(False, True, message)


def _loop(pb: PathProblem, rule: StepRule) -> bool:
    rows = pb.rows
    cur = pb.first_point()
    ds = rule.ds0
    cos_max = np.cos(np.radians(rule.max_angle_deg))
    t = pb.first_direction(cur, pb.metric()) if rule.mode != "natural" else None
    prev: Solution | None = None
    turns = 0  # halvings of this step for a sharp turn
    arc = 0  # hybrid mode: arc-length steps left (a fold in the parameter)
    hist = [cur.y]
    s_top, since_top = float(cur.param), 0
    n_solves = 0
    while True:
        if rule.end == "clip" and not cur.param < pb.end * (1 - 1e-14):
            return True
        if rows.n >= rule.max_points:
            raise Stop(pb.say("max_points", at=cur), failed=False)
        if rule.max_solves is not None:
            n_solves += 1
            if n_solves > rule.max_solves:  # refused and halved steps: never without end
                raise Stop(pb.say("max_solves", n_solves=n_solves - 1), failed=True)
        m = pb.metric() if rule.mode != "natural" else None
        arcstep = rule.mode == "arclength" or arc > 0
        if m is not None and prev is not None:
            if rule.predictor == "tangent":
                tt = pb.tangent(cur)
                tt /= norm(tt, m)
                t = tt if np.sum(m * m * tt * t) >= 0 else -tt
            else:  # secant (and the constant predictor's constraint)
                t = (cur.y - prev.y) / norm(cur.y - prev.y, m)
        yp = None
        if arcstep:
            yp = cur.y + ds * t
            new = pb.solve_plane(cur.y if rule.predictor == "constant" else yp, yp, t, m)
            if not new.converged and prev is not None and rule.fallbacks:
                new = _fallbacks(pb, cur, prev, yp, t, m, ds)
        else:
            new = pb.natural_step(cur, prev, t, ds)
        reject = not new.converged
        if new.converged and m is not None:
            step = new.y - cur.y
            cosang = np.sum(m * m * step * t) / max(norm(step, m), 1e-300)
            sharp = rule.max_change is not None and pb.change(cur, new) > rule.max_change
            sharp = sharp or (arcstep and cosang < cos_max)
            if rule.max_correction is not None and yp is not None:
                # how far the corrector moved off the predictor (onto another branch?)
                sharp = sharp or norm(new.y - yp, m) / ds > rule.max_correction
            if sharp and ds > 2 * rule.ds_min and turns < rule.max_turns:
                # halve (a few times at most; what is still sharp then is a kink of the
                # path, where a stick/slip or contact transition changes its slope)
                turns += 1
                if not rule.turn_is_failure:
                    ds *= 0.5
                    continue
                reject = True
            elif rule.reject_backwards and cosang < 0.0 and prev is not None:
                reject = True  # back along the path behind us: never accepted
            elif (
                rule.retrace_tol is not None
                and len(hist) > 2
                and min(norm(new.y - h, m) for h in hist[:-2]) < rule.retrace_tol * ds
            ):
                reject = True  # retracing the path already computed
        if reject:
            ds *= 0.5
            if rule.mode == "hybrid" and not arc and ds < rule.hybrid_switch and prev is not None:
                arc, ds = rule.hybrid_arc, rule.hybrid_ds  # natural steps stall: a fold?
                continue
            if rule.refresh_on_failure:
                pb.refresh()
            if ds < rule.ds_min:
                raise Stop(pb.say("failed", at=cur, sol=new), failed=True)
            continue
        turns = 0
        if rule.end != "clip" and (
            new.param >= pb.end if rule.end_inclusive else new.param > pb.end
        ):
            return reach_end(pb, rule, cur, new)
        if new.param < pb.start * (1 - rule.start_rtol):
            raise Stop(pb.say("below_start"), failed=False)
        if arc:  # back to natural steps once the parameter increases again
            arc = arc - 1 if new.param > cur.param else rule.hybrid_arc
            if rule.fold_drop is not None and new.param < s_top - rule.fold_drop:
                raise Stop(pb.say("fold_drop", top=s_top), failed=False)
        if rule.fold_points is not None:
            if new.param > s_top:
                s_top, since_top = float(new.param), 0
            else:
                since_top += 1
                if since_top > rule.fold_points:
                    raise Stop(pb.say("fold_points", top=s_top), failed=False)
        try:
            pb.record(new)
        except LostContact:
            if (
                rule.close_in is not None
                and new.param - cur.param > rule.close_in
                and ds > 2 * rule.ds_min
            ):
                ds *= 0.5  # close in on the loss of contact
                continue
            raise
        prev, cur = cur, new
        if rule.retrace_tol is not None:
            hist.append(cur.y)
        pb.after_point()
        ds, refresh = rule.grow(ds, new.its)
        if refresh:  # a slow corrector: a fresh linearisation for the next step
            pb.refresh()


def _fallbacks(pb, cur, prev, yp, t, m, ds) -> Solution:
    """Where the plane ahead misses a path that turns sharply at a kink (a fold at a
    stick/slip or contact transition): the sphere of radius ``ds``, then the plane
    along the secant with its parameter part reversed."""
    res = pb.solve_sphere(cur, yp, t, m, ds)
    if res.converged and norm(res.y - prev.y, m) < 0.5 * ds:
        res.converged = False  # the sphere's other cut: back where we came from
    if res.converged:
        return res
    # a fold exactly at a kink can turn the path back almost on itself: keep the point
    # only if it is off the incoming piece
    tr = t.copy()
    tr[-1] = -tr[-1]
    tr /= norm(tr, m)
    ypr = cur.y + ds * tr
    res = pb.solve_plane(ypr, ypr, tr, m)
    if res.converged:
        d = res.y - cur.y
        along = np.sum(m * m * d * t)  # the incoming piece runs along -t
        off = norm(d - along * t, m)
        if along >= 0 or off < 0.05 * norm(d, m):
            res.converged = False
            res.reason = "converged back onto the incoming branch (rejected)"
    return res


def reach_end(pb: PathProblem, rule: StepRule, cur: Solution, new: Solution) -> bool:
    """The last point exactly at the end of the range, between ``cur`` and ``new`` (which
    passed it)."""
    guess = pb.end_guess(cur, new)
    end = pb.solve_at(guess, pb.end)
    if rule.end == "once":
        if end.converged:
            pb.record(end, at_end=True)
        else:
            pb.record_past_end(cur, new)
        return True
    # "retry": with a fresh linearisation, from the step's own solution, then by steps
    # from the last point (halved while they fail)
    for g in (guess, new.raw):
        if end.converged:
            break
        pb.refresh()
        end = pb.solve_at(g, pb.end)
    pc, sc, dp = cur.raw, cur.param, pb.end - cur.param
    while not end.converged and dp > 1e-3 * (pb.end - cur.param):  # a kink before the end
        st = min(sc + dp, pb.end)
        pb.refresh()
        trial = pb.solve_at(pc, st)
        if trial.converged:
            pc, sc = trial.raw, st
            if st >= pb.end:
                end = trial
                break
        else:
            dp *= 0.5
            end = trial
    if not end.converged:
        raise Stop(pb.say("end_failed", at=cur, sol=end), failed=True)
    pb.record(end, at_end=True)
    return True
