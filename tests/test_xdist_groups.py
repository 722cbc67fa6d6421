"""`make test` shares expensive study fixtures through pytest-xdist groups.

With `--dist loadgroup` every test marked ``xdist_group(name)`` must run on one
worker (its node id carries ``@name``); when the pinned pytest and
pytest-xdist disagree on how node ids are built (pytest 9 with xdist 3.8),
the marks are silently ignored and each worker recomputes the shared study
fixtures. Outside `--dist loadgroup` there is no grouping to check.
"""

import pytest

pytestmark = pytest.mark.xdist_group("groupcheck")


def test_xdist_groups_are_honoured(request):
    if not getattr(request.config.option, "loadgroup", False):
        return  # a plain (serial) run: nothing is distributed
    assert request.node.nodeid.endswith("@groupcheck"), request.node.nodeid
