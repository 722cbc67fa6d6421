"""The uncertainty study's records and statistics: distributions, the design, Sobol indices.

Plain numbers, no solving: an input's :class:`Distribution` (parsed from the
study file), the Saltelli :class:`Design` (SALib) and its rows, the
statistics of an output over the design (percentiles, exceedance), SALib's
Sobol indices, and the answer tables built from an analysis. The study
(``workbench.studies.kinds.uncertainty.compute``) computes the samples; the figures
(``workbench.studies.kinds.uncertainty.figures``) and the report draw these.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError

INPUTS = ("mu", "cf", "kt", "kn", "damping", "seat-tilt")


INPUT_LABELS = {
    "mu": "friction coefficient mu",
    "cf": "CF factor",
    "kt": "kt factor",
    "kn": "kn factor",
    "damping": "modal damping ratio",
    "seat-tilt": "seat tilt, deg",
}


QUANTITIES = (
    ("peak_amplitude_mm", "peak amplitude", "mm"),
    ("peak_frequency_hz", "resonance frequency", "Hz"),
    ("friction_energy_mj", "friction energy per cycle", "mJ"),
)


DIST_KINDS = ("uniform", "normal", "lognormal")


@dataclass(frozen=True)
class Distribution:
    """One input's distribution: ``kind`` with parameters ``a``, ``b`` and bounds ``lo``, ``hi``.

    uniform: ``a`` = lo, ``b`` = hi; normal: mean ``a``, standard deviation
    ``b``; lognormal: median ``a``, standard deviation of ``ln x`` ``b``.
    Bounds (None: unbounded) truncate the normal and lognormal.
    """

    kind: str
    a: float
    b: float
    lo: float | None = None
    hi: float | None = None

    def _frozen(self):
        from scipy import stats

        if self.kind == "uniform":
            return stats.uniform(loc=self.a, scale=self.b - self.a)
        if self.kind == "normal":
            return stats.norm(loc=self.a, scale=self.b)
        return stats.lognorm(s=self.b, scale=self.a)

    def ppf(self, u: np.ndarray) -> np.ndarray:
        """Inverse CDF of the (truncated) distribution at ``u`` in [0, 1]."""
        d = self._frozen()
        u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
        if self.kind == "uniform" or (self.lo is None and self.hi is None):
            return d.ppf(u)
        f_lo = d.cdf(self.lo) if self.lo is not None else 0.0
        f_hi = d.cdf(self.hi) if self.hi is not None else 1.0
        x = d.ppf(f_lo + u * (f_hi - f_lo))
        return np.clip(
            x,
            self.lo if self.lo is not None else -np.inf,
            self.hi if self.hi is not None else np.inf,
        )

    @property
    def support(self) -> tuple[float, float]:
        if self.kind == "uniform":
            return self.a, self.b
        return tuple(float(v) for v in self.ppf(np.array([0.0, 1.0])))  # type: ignore[return-value]

    def describe(self) -> str:
        bounds = (
            ""
            if self.kind == "uniform" or (self.lo is None and self.hi is None)
            else f", truncated to [{self.lo:g}, {self.hi:g}]"
        )
        if self.kind == "uniform":
            return f"uniform on [{self.a:g}, {self.b:g}]"
        if self.kind == "normal":
            return f"normal, mean {self.a:g}, sd {self.b:g}{bounds}"
        return f"lognormal, median {self.a:g}, sigma(ln) {self.b:g}{bounds}"


def parse_distribution(name: str, text: str) -> Distribution:
    """``"uniform LO HI"``, ``"normal MEAN SD [LO HI]"``, ``"lognormal MEDIAN SIGMA [LO HI]"``."""
    allowed = (
        "'uniform LO HI', 'normal MEAN SD [LO HI]' or 'lognormal MEDIAN SIGMA_LN "
        "[LO HI]' (numbers separated by spaces or commas)"
    )
    parts = str(text).replace(",", " ").split()
    if not parts or parts[0].lower() not in DIST_KINDS:
        raise InputError(name, text, allowed)
    kind = parts[0].lower()
    try:
        nums = [float(x) for x in parts[1:]]
    except ValueError:
        raise InputError(name, text, allowed) from None
    if len(nums) not in ((2,) if kind == "uniform" else (2, 4)):
        raise InputError(name, text, allowed)
    if not all(math.isfinite(x) for x in nums):
        raise InputError(name, text, "finite numbers")
    a, b = nums[:2]
    lo, hi = (nums[2], nums[3]) if len(nums) == 4 else (None, None)
    if kind == "uniform" and not a < b:
        raise InputError(name, text, "uniform LO HI with LO < HI")
    if kind != "uniform" and b <= 0:
        raise InputError(name, text, "a positive spread (sd or sigma_ln)")
    if kind == "lognormal" and a <= 0:
        raise InputError(name, text, "a positive median")
    if lo is not None and not lo < hi:
        raise InputError(name, text, "bounds LO < HI")
    if lo is not None and kind == "lognormal" and lo <= 0:
        raise InputError(name, text, "a positive lower bound for a lognormal")
    if lo is not None and not lo <= a <= hi:
        raise InputError(name, text, "bounds around the mean or median")
    return Distribution(kind, a, b, lo, hi)


@dataclass(frozen=True)
class Design:
    """A Saltelli design: ``unit`` (rows x D) on [0, 1], ``values`` in physical units.

    Row ``r`` belongs to base point ``r // (D + 2)``; within it, role 0 is
    ``A``, roles 1..D are ``AB_j`` (``A`` with column ``j - 1`` from ``B``)
    and role D + 1 is ``B`` (SALib's layout without second order).
    """

    names: tuple[str, ...]
    unit: np.ndarray
    values: np.ndarray
    n_base: int
    seed: int

    @property
    def n_rows(self) -> int:
        return int(self.unit.shape[0])

    @property
    def block(self) -> int:
        return len(self.names) + 2

    def role(self, r: int) -> str:
        j = r % self.block
        return "A" if j == 0 else "B" if j == self.block - 1 else f"AB{j}"

    @property
    def ab_rows(self) -> np.ndarray:
        """Rows of ``A`` and ``B``: 2 N draws of the joint distribution."""
        r = np.arange(self.n_rows)
        j = r % self.block
        return r[(j == 0) | (j == self.block - 1)]

    def problem(self) -> dict[str, Any]:
        """SALib's problem on the unit cube (the indices do not change under the inverse CDFs)."""
        return {
            "num_vars": len(self.names),
            "names": list(self.names),
            "bounds": [[0.0, 1.0]] * len(self.names),
        }


def make_design(dists: dict[str, Distribution], n: int, seed: int) -> Design:
    """SALib's Saltelli design (first and total order) of ``n`` base points."""
    import warnings

    from SALib.sample import sobol

    names = tuple(dists)
    problem = {"num_vars": len(names), "names": list(names), "bounds": [[0.0, 1.0]] * len(names)}
    with warnings.catch_warnings():  # "not a power of 2": allowed, said in the docs
        warnings.simplefilter("ignore")
        unit = sobol.sample(problem, int(n), calc_second_order=False, scramble=True, seed=int(seed))
    values = np.column_stack([dists[k].ppf(unit[:, j]) for j, k in enumerate(names)])
    return Design(names, unit, values, int(n), int(seed))


def statistics(y: np.ndarray, threshold: float | None = None) -> dict[str, float]:
    """Mean, sd, percentiles and exceedance probability of the finite values of ``y``."""
    y = np.asarray(y, dtype=float)
    ok = y[np.isfinite(y)]
    out: dict[str, float] = {"n": int(ok.size), "n_missing": int(y.size - ok.size)}
    if ok.size == 0:
        return out
    out.update(
        {
            "mean": float(ok.mean()),
            "sd": float(ok.std(ddof=1)) if ok.size > 1 else 0.0,
            "min": float(ok.min()),
            "p05": float(np.quantile(ok, 0.05)),
            "p50": float(np.quantile(ok, 0.5)),
            "p95": float(np.quantile(ok, 0.95)),
            "max": float(ok.max()),
        }
    )
    if threshold is not None:
        out["p_exceed"] = float(np.mean(ok > threshold))
    return out


N_BOOT = 2000


def ranking_confidence(
    peaks: np.ndarray, names: list[str], seed: int = 0, n_boot: int = N_BOOT
) -> dict[str, Any]:
    """How sure the smallest-95th-percentile verdict is, by a paired bootstrap.

    ``peaks`` (n_samples, n_dampers): every damper's peak on the SAME samples
    (rows). Rows are resampled with replacement ``n_boot`` times; each time
    the 95th percentile of every column is taken and the smallest wins.
    Returns the winner on the data, the share of resamples it also wins
    (``confidence``; near 1/n_dampers means the samples cannot tell), and a
    90 % interval (5th-95th percentile of the resampled values) of each
    damper's 95th percentile.
    """
    P = np.asarray(peaks, dtype=float)
    if P.ndim != 2 or P.shape[0] < 2 or P.shape[1] < 2:
        return {}
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, P.shape[0], size=(n_boot, P.shape[0]))
    q = np.quantile(P[idx], 0.95, axis=1)  # (n_boot, n_dampers)
    best = int(np.argmin(np.quantile(P, 0.95, axis=0)))
    wins = np.bincount(np.argmin(q, axis=1), minlength=P.shape[1]) / n_boot
    lo, hi = np.quantile(q, 0.05, axis=0), np.quantile(q, 0.95, axis=0)
    return {
        "winner": names[best],
        "confidence": float(wins[best]),
        "wins": {n: float(w) for n, w in zip(names, wins, strict=True)},
        "p95_ci90_mm": {n: [float(a), float(b)] for n, a, b in zip(names, lo, hi, strict=True)},
        "n_samples": int(P.shape[0]),
        "n_boot": int(n_boot),
    }


def sobol_indices(design: Design, y: np.ndarray, seed: int = 0) -> dict[str, Any]:
    """SALib's first- and total-order Sobol indices of ``y`` over the design's rows.

    A base point with a missing output (NaN) is dropped whole (SALib needs
    every row of a base point); ``n_used`` says how many were kept.
    """
    from SALib.analyze import sobol

    y = np.asarray(y, dtype=float)
    if y.shape != (design.n_rows,):
        raise InputError("outputs", y.shape, f"({design.n_rows},) one per design row")
    blocks = y.reshape(design.n_base, design.block)
    keep = np.all(np.isfinite(blocks), axis=1)
    out: dict[str, Any] = {
        "names": list(design.names),
        "n_used": int(keep.sum()),
        "n_base": design.n_base,
    }
    if keep.sum() < 2 or np.ptp(blocks[keep]) == 0.0:
        nan = [float("nan")] * len(design.names)
        out.update(S1=nan, S1_conf=nan, ST=nan, ST_conf=nan)
        return out
    import warnings

    with warnings.catch_warnings():  # pandas FutureWarning from inside SALib 1.5
        warnings.simplefilter("ignore", FutureWarning)
        res = sobol.analyze(
            design.problem(),
            blocks[keep].ravel(),
            calc_second_order=False,
            num_resamples=200,
            seed=seed,
        )
    for k in ("S1", "S1_conf", "ST", "ST_conf"):
        out[k] = [float(v) for v in res[k]]
    return out


def driver(ind: dict[str, Any]) -> str | None:
    """The input with the largest total-order index (None when none is finite)."""
    st = np.asarray(ind.get("ST", []), dtype=float)
    if st.size == 0 or not np.isfinite(st).any():
        return None
    return ind["names"][int(np.nanargmax(st))]


NEGLIGIBLE_ST = 0.05  # an input whose total index is below this with its half-width


def driver_verdict(ind: dict[str, Any]) -> dict[str, Any]:
    """The driver and whether the samples tell it apart from the other inputs.

    ``negligible``: the inputs whose ``ST + conf`` is below
    :data:`NEGLIGIBLE_ST` (SALib's 95 % bootstrap half-widths): ruled out as
    drivers at any N. ``contenders``: the other inputs, not negligible, whose
    total index reaches the driver's lower bound (``ST + conf >= ST_driver -
    conf_driver``): with these samples they may drive the spread as much;
    ``resolved`` when there are none.
    """
    name = driver(ind)
    if name is None:
        return {"driver": None, "resolved": False, "contenders": [], "negligible": []}
    names = list(ind["names"])
    st = np.asarray(ind["ST"], dtype=float)
    cf = np.nan_to_num(np.asarray(ind.get("ST_conf", np.zeros_like(st)), dtype=float), nan=np.inf)
    j = names.index(name)
    lo = st[j] - cf[j]
    others = [i for i in range(len(names)) if i != j]
    negligible = [names[i] for i in others if st[i] + cf[i] < NEGLIGIBLE_ST]
    contenders = [names[i] for i in others if st[i] + cf[i] >= lo and names[i] not in negligible]
    return {
        "driver": name,
        "resolved": not contenders,
        "contenders": contenders,
        "negligible": negligible,
    }


def analysis_summary(a: dict[str, Any]) -> dict[str, Any]:
    return {
        "thresholds_mm": a["thresholds_mm"],
        "groups": answer_rows(a),
        "smallest_p95_peak": a["robust"],
        "ranking_confidence": {fam: c.get("confidence") for fam, c in a.get("ranking", {}).items()},
    }


def _p95(r: dict[str, Any]) -> float:
    return r["stats"]["peak_amplitude_mm"].get("p95_common", np.inf)


def headline(a: dict[str, Any]) -> list[str]:
    lines = []
    for fam, best in a["robust"].items():
        grp = {r["damper"]: r for r in a["groups"] if r["family"] == fam}
        if len(grp) < 2:
            continue
        n = grp[best]["stats"]["peak_amplitude_mm"]["n_common"]
        others = ", ".join(f"{d} {_p95(r):.4g} mm" for d, r in grp.items() if d != best)
        conf = a.get("ranking", {}).get(fam, {}).get("confidence")
        verdict = ""
        if conf is not None:
            verdict = f"; it also wins {100 * conf:.0f} % of {N_BOOT} bootstrap resamples"
            if conf < 0.9:
                verdict += " (the samples cannot tell the dampers apart: raise uq-samples)"
            if n < 20:
                verdict += (
                    f"; with {n} draws the 95th percentile is near the largest draw and "
                    "the resamples cannot see tails the draws missed"
                )
        lines.append(
            f"{fam}: the {best} has the smallest 95th-percentile peak, "
            f"{_p95(grp[best]):.4g} mm ({others}; over the {n} samples every damper "
            f"solved{verdict})"
        )
    for r in a["groups"]:
        st = r["stats"]["peak_amplitude_mm"]
        if "p95" not in st:
            lines.append(f"{r['damper']}, {r['family']}: no peak in any sample")
            continue
        pe = st.get("p_exceed")
        ver = driver_verdict(r["indices"]["peak_amplitude_mm"])
        told = (
            f" (not told apart from {', '.join(ver['contenders'])} with these samples)"
            if ver["contenders"]
            else ""
        )
        lines.append(
            f"{r['damper']}, {r['family']}: peak median {st['p50']:.4g} mm, 95th percentile "
            f"{st['p95']:.4g} mm, P(peak > {r['threshold_mm']:.3g} mm) = "
            f"{pe:.2f}; driven by {r['driver'] or '?'}{told}"
            + (f" ({r['n_failed']} solves stopped early: left out)" if r["n_failed"] else "")
        )
    return lines


def answer_rows(a: dict[str, Any]) -> list[dict[str, Any]]:
    """Per family, the dampers ranked by 95th-percentile peak (common samples), the driver."""
    rows = []
    for fam in dict.fromkeys(r["family"] for r in a["groups"]):
        grp = [r for r in a["groups"] if r["family"] == fam]
        rank = a.get("ranking", {}).get(fam, {})
        for k, r in enumerate(sorted(grp, key=_p95)):
            st = r["stats"]["peak_amplitude_mm"]
            ind = r["indices"]["peak_amplitude_mm"]
            j = ind["names"].index(r["driver"]) if r["driver"] else None
            ver = driver_verdict(ind)
            rows.append(
                {
                    "family": fam,
                    "rank": k + 1,
                    "damper": r["damper"],
                    "peak_p50_mm": st.get("p50"),
                    "peak_p95_common_mm": st.get("p95_common"),
                    "peak_p95_ci90_mm": rank.get("p95_ci90_mm", {}).get(r["damper"]),
                    "wins_share": rank.get("wins", {}).get(r["damper"]),
                    "n_common": st.get("n_common"),
                    "peak_p95_mm": st.get("p95"),
                    "threshold_mm": r["threshold_mm"],
                    "p_exceed": st.get("p_exceed"),
                    "driver": r["driver"],
                    "driver_ST": ind["ST"][j] if j is not None else None,
                    "driver_ST_conf": ind["ST_conf"][j] if j is not None else None,
                    "driver_resolved": ver["resolved"],
                    "driver_contenders": "; ".join(ver["contenders"]),
                    "negligible_inputs": "; ".join(ver["negligible"]),
                    "failed_solves": r["n_failed"],
                }
            )
    return rows


def stats_rows(a: dict[str, Any]) -> list[dict[str, Any]]:
    rows = []
    for r in a["groups"]:
        for q, label, unit in QUANTITIES:
            st = r["stats"][q]
            rows.append(
                {
                    "damper": r["damper"],
                    "family": r["family"],
                    "quantity": f"{label}, {unit}",
                    **{k: (round(v, 6) if isinstance(v, float) else v) for k, v in st.items()},
                }
            )
    return rows


def index_rows(a: dict[str, Any]) -> list[dict[str, Any]]:
    rows = []
    for r in a["groups"]:
        for q, label, _unit in QUANTITIES:
            ind = r["indices"][q]
            for j, name in enumerate(ind["names"]):
                rows.append(
                    {
                        "damper": r["damper"],
                        "family": r["family"],
                        "quantity": label,
                        "input": name,
                        "S1": round(ind["S1"][j], 4),
                        "S1_conf": round(ind["S1_conf"][j], 4),
                        "ST": round(ind["ST"][j], 4),
                        "ST_conf": round(ind["ST_conf"][j], 4),
                        "base_points_used": ind["n_used"],
                    }
                )
    return rows
