"""A contact law declares its parameters once: the study options, the contact parameters,
the report and the cache key read that declaration (workbench/contact/laws/)."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys

import pytest
from conftest import ROOT

from workbench.assembly.params import ContactParams, load_contact_params
from workbench.contact.law_params import COMMON, law_params, params_of
from workbench.contact.laws import REGISTRY
from workbench.errors import InputError
from workbench.post.provenance import contact_args
from workbench.studies.engine.plan import MODEL_KEYS
from workbench.studies.engine.spec import BY_NAME, resolve

# a law with a parameter of its own; its step is the decoupled law's (the hbm end, which
# would pass eta to the step, is not part of this check)
LAW = '''"""A test law with its own parameter eta."""
from .jenkins import step  # noqa: F401

NAME = "etalaw"
N_STATE = 4
PARAMS = (
    {"name": "eta", "help": "a test parameter", "unit": "1/s", "lo": 0.0, "hi": 1.0,
     "default": 0.1},
)
'''

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
    pkg = tmp_path / "workbench"
    shutil.copytree(ROOT / "workbench", pkg, ignore=shutil.ignore_patterns("__pycache__", "*.so"))
    shutil.copytree(ROOT / "geometry", tmp_path / "geometry")
    (pkg / "contact" / "laws" / "etalaw.py").write_text(LAW)
    r = subprocess.run(
        [sys.executable, "-c", CHECK], capture_output=True, text=True, cwd=tmp_path, timeout=300
    )
    assert r.returncode == 0, r.stderr
    got = json.loads(r.stdout)
    assert got["params"] == ["mu", "eta"] and got["of"] == ["mu", "eta"]
    assert got["option"] == ["float", 0.0, 1.0, "1/s", "contact", "model", "a test parameter"]
    assert "eta" in got["refused"] and "1" in got["refused"]
    assert got["default"] == {"eta": 0.1} and got["given"] == {"eta": 0.25}
    assert got["source"] == "option" and got["keyed"] is True


def test_a_laws_own_parameters_reach_the_contact_elements():
    """Per pair in the assembled model, per element in the solver's contact record (kept
    through concat and with_params); the step does not read them yet (the hbm end)."""
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
