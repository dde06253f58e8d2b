"""``examples/balance_fourbar.py``: counterweights optimized with JAX gradients reach the
Berkof-Lowen full force-balance conditions (closed form), and ``md.inverse`` of the balanced
mechanism confirms the shaking force is gone (a second method: the ground reactions)."""

import importlib.util
import sys

from fixtures import EXAMPLES


def _example():
    path = EXAMPLES / "balance_fourbar.py"
    spec = importlib.util.spec_from_file_location("balance_fourbar", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def test_counterweights_reach_berkof_lowen_and_cancel_the_shaking_force():
    merit = _example().main()
    # The optimum is the closed form's, and the shaking force is gone.
    assert merit["relative_difference"] <= 1e-6
    assert merit["ratio"] <= 1e-8
    # The reactions of md.inverse agree: the unbalanced shaking force by Newton's sum m a and
    # by the ground pivots' reactions, and the balanced one vanishes by the reactions too.
    assert abs(merit["unbalanced_by_reactions"] / merit["unbalanced"] - 1) <= 1e-9
    assert merit["unbalanced"] > 1.0  # a real shaking force to cancel [N]
    assert merit["reaction_ratio"] <= 1e-8
