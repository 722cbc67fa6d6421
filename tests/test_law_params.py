"""A contact law declares its parameters once: the study options, the contact parameters,
the report and the cache key read that declaration (workbench/contact/laws/)."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys

import numpy as np
import pytest
from conftest import ROOT

from workbench.assembly.params import ContactParams, load_contact_params
from workbench.contact.law_params import COMMON, law_params, params_of
from workbench.contact.laws import REGISTRY
from workbench.errors import InputError
from workbench.post.provenance import contact_args
from workbench.studies.engine.plan import MODEL_KEYS
from workbench.studies.engine.spec import BY_NAME, resolve

# a law with a parameter of its own: the decoupled law with the slip limit eta mu N (its
# step reads eta from lp, the row of the element's own parameters)
LAW = '''"""A test law with its own parameter eta: Jenkins elements slipping at eta mu N."""
from numba import njit

from .jenkins import step as jenkins_step

NAME = "etalaw"
N_STATE = 4
PARAMS = (
    {"name": "eta", "help": "a test parameter", "unit": "", "lo": 0.0, "hi": 1.0,
     "default": 0.1},
)


@njit(cache=True)
def step(u, s, mu, kt1, kt2, kn, n0, lp, want_jac, f, s_new, Fu, Fs, Su, Ss):
    return jenkins_step(u, s, mu * lp[0], kt1, kt2, kn, n0, lp, want_jac, f, s_new, Fu, Fs,
                        Su, Ss)
'''


def _copy_with_law(tmp_path):
    """A copy of the package (and its geometry files) with the law module dropped in."""
    pkg = tmp_path / "workbench"
    shutil.copytree(ROOT / "workbench", pkg, ignore=shutil.ignore_patterns("__pycache__", "*.so"))
    shutil.copytree(ROOT / "geometry", tmp_path / "geometry")
    (pkg / "contact" / "laws" / "etalaw.py").write_text(LAW)


def _run(code: str, cwd, *args: str) -> dict:
    r = subprocess.run(
        [sys.executable, "-c", code, *args], capture_output=True, text=True, cwd=cwd, timeout=600
    )
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout.strip().splitlines()[-1])


CHECK = """
import json
from workbench.assembly.params import load_contact_params, contact_sources
from workbench.contact.law_params import law_params, params_of
from workbench.post.provenance import contact_args
from workbench.studies.engine.plan import MODEL_KEYS
from workbench.studies.engine.spec import BY_NAME, resolve
from workbench.errors import InputError
o = BY_NAME["eta"]
try:
    resolve({"eta": 5.0})
    refused = ""
except InputError as e:
    refused = str(e)
print(json.dumps({
    "params": [p.name for p in law_params()],
    "of": [p.name for p in params_of("etalaw")],
    "option": [o.kind, o.lo, o.hi, o.unit, o.group, o.role, o.help],
    "refused": refused,
    "default": load_contact_params().law,
    "given": load_contact_params(**contact_args({"eta": 0.25})).law,
    "source": contact_sources(eta=0.25)["eta"],
    "keyed": "eta" in MODEL_KEYS,
}))
"""


def test_every_law_reads_the_common_friction_coefficient():
    assert [p.name for p in COMMON] == ["mu"]
    assert all(params_of(name) == COMMON for name in REGISTRY)
    assert [p.name for p in law_params()] == ["mu"]  # no built-in law has one of its own


def test_the_friction_coefficient_option_and_field_are_its_declaration():
    (mu,) = COMMON
    o = BY_NAME["mu"]
    assert (o.lo, o.hi, o.help, o.role, o.optional) == (mu.lo, mu.hi, mu.help, "model", True)
    assert ContactParams().mu == mu.default and "mu" in MODEL_KEYS
    with pytest.raises(InputError, match="mu"):
        resolve({"mu": 2.5})
    assert load_contact_params(**contact_args({"mu": 0.3})).mu == 0.3
    # no law has parameters of its own: the record's cache key is what it was
    assert "law" not in ContactParams().key() and ContactParams().law == {}


def test_a_law_with_its_own_parameter_is_one_module(tmp_path):
    """Drop a law module declaring ``eta`` into a copy of the package: it becomes a study
    option (range, unit, help), a [contact] value with its default, a case's contact
    parameter (the pipeline's path) and a part of the model's cache key."""
    _copy_with_law(tmp_path)
    got = _run(CHECK, tmp_path)
    assert got["params"] == ["mu", "eta"] and got["of"] == ["mu", "eta"]
    assert got["option"] == ["float", 0.0, 1.0, "", "contact", "model", "a test parameter"]
    assert "eta" in got["refused"] and "1" in got["refused"]
    assert got["default"] == {"eta": 0.1} and got["given"] == {"eta": 0.25}
    assert got["source"] == "option" and got["keyed"] is True


def test_a_laws_own_parameters_reach_the_contact_elements():
    """Per pair in the assembled model, per element in the solver's contact record (kept
    through concat and with_params); the march hands them to the law's step as ``lp``."""
    from types import SimpleNamespace

    import numpy as np
    import scipy.sparse as sp

    from workbench.assembly.model import AssembledModel
    from workbench.contact.elements import ContactElements

    pairs = SimpleNamespace(
        W=sp.identity(6, format="csr"),
        mu=np.full(2, 0.4),
        kt=np.full(2, 10.0),
        kn=np.full(2, 20.0),
        n0=np.full(2, 1.0),
        law={"eta": np.array([0.1, 0.2])},
    )
    el = AssembledModel.contact_elements(pairs)
    assert el.law_params["eta"].tolist() == [0.1, 0.2] and el.mu.tolist() == [0.4, 0.4]
    both = ContactElements.concat([el, el.with_params(law_params={"eta": 0.3})])
    assert both.law_params["eta"].tolist() == [0.1, 0.2, 0.3, 0.3]
    with pytest.raises(InputError, match="eta"):
        el.with_params(law_params={"eta": [0.1, 0.2, 0.3]})  # one value per element
    with pytest.raises(InputError, match="law_params"):
        ContactElements.concat([el, el.with_params(law_params={})])


# a model file of a mass on a spring with one Jenkins-type element to the ground (a single
# tangential DOF, constant normal load): stuck at 141 Hz, free at 100 Hz
MODEL = """
[model]
matrices = "m.npz"
damping_ratio = 0.005
[excitation]
dofs = [0]
amplitudes_n = [1.0]
[band]
start_hz = 80.0
end_hz = 170.0
[hbm]
harmonics = [0, 1, 2, 3]
nt = 64
[output]
dofs = [0]
[[contact]]
dofs = [[0]]
kt_n_per_m = 39478.4
n0_n = 2.0
"""

FORCED = """
import dataclasses, json, sys
from pathlib import Path
import numpy as np
from workbench.errors import InputError
from workbench.hbm import frequency_response, load_frf_model

np.savez("m.npz", M=[[0.1]], K=[[39478.4]])
base = Path("model.toml").read_text()
compiled = sys.argv[1]


def model(extra):
    Path("model.toml").write_text(base + extra)
    return load_frf_model("model.toml")


def response(extra):
    fm = model(extra)
    opts = dataclasses.replace(fm.options, compiled=compiled)
    br = frequency_response(fm.system, fm.f1, 1.0, fm.band_hz, fm.outputs,
                            harmonics=fm.harmonics, nt=fm.nt, options=opts)
    assert br.completed and not br.failed, br.message
    return dict(mode=br.stats["mode"], amp=br.out_amp[:, 0].tolist(),
                freq=br.freq_hz.tolist(), energy=br.friction_energy.sum(axis=1).tolist())


def refused(extra):
    try:
        model(extra)
    except InputError as e:
        return str(e)
    return ""


print(json.dumps({
    "lp": model('law = "etalaw"\\neta = 0.5').system.contacts.lp.tolist(),
    "default": model('law = "etalaw"').system.contacts.lp.tolist(),
    "none": model("").system.contacts.lp.shape,
    "range": refused('law = "etalaw"\\neta = 5.0'),
    "other": refused("eta = 0.5"),
    "eta": response('mu = 0.6\\nlaw = "etalaw"\\neta = 0.5'),
    "mu": response("mu = 0.3"),
    "more": response('mu = 0.6\\nlaw = "etalaw"\\neta = 1.0'),
}))
"""


def _forced(tmp_path, compiled: str) -> dict:
    _copy_with_law(tmp_path)
    (tmp_path / "model.toml").write_text(MODEL)
    return _run(FORCED, tmp_path, compiled)


def _same_response(a: dict, b: dict) -> None:
    assert len(a["freq"]) == len(b["freq"]) > 10
    for k in ("freq", "amp", "energy"):
        np.testing.assert_allclose(a[k], b[k], rtol=1e-9, atol=1e-12 * max(map(abs, b[k])))


def _stiffer(a: dict, b: dict) -> None:
    """``a`` slips at a higher limit than ``b``: it stays stuck longer, so its peak is lower
    and nearer the stuck resonance (141 Hz) than the free one (100 Hz)."""
    ia, ib = np.argmax(a["amp"]), np.argmax(b["amp"])
    assert a["amp"][ia] < 0.5 * b["amp"][ib] and a["freq"][ia] > b["freq"][ib] + 5.0


def test_a_laws_own_parameter_reaches_its_step_and_the_response(tmp_path):
    """The dropped-in law slips at eta mu N: read from a model file (its default when the
    file has none, refused out of range or for a law that does not declare it), its forced
    response with (mu 0.6, eta 0.5) is the decoupled law's with mu 0.3, and eta 1 gives
    another one (a higher slip limit: a stiffer, lower peak)."""
    got = _forced(tmp_path, "off")
    assert got["lp"] == [[0.5]] and got["default"] == [[0.1]] and got["none"] == [1, 0]
    assert "contact[0].eta" in got["range"] and "1" in got["range"]
    assert "contact[0].eta" in got["other"] and "decoupled" in got["other"]
    assert got["eta"]["mode"] == got["mu"]["mode"] == "newton"
    _same_response(got["eta"], got["mu"])
    _stiffer(got["more"], got["eta"])


# slow: numba compiles the small-system kernels of the new law just in time (a minute or two)
@pytest.mark.slow
def test_a_laws_own_parameter_reaches_the_compiled_kernels(tmp_path):
    """The same check on the compiled small-system path (lp through its kernels)."""
    got = _forced(tmp_path, "auto")
    assert got["eta"]["mode"] == got["mu"]["mode"] == "compiled"
    _same_response(got["eta"], got["mu"])
    _stiffer(got["more"], got["eta"])
