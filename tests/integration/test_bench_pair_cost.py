"""The per-pair-kind detection benchmark's plumbing (validation.bench.pair_cost): a scene
per pair kind with the side pressed into the surface, both routes timed at the same
state and agreeing on its gap."""

import pytest

from validation.bench import pair_cost


@pytest.mark.parametrize("pair, bilateral", [(("sphere", "2s"), False), (("point", "plane"), False),
                                             (("point", "1s"), True)])
def test_a_row_times_both_routes_at_a_closed_contact(pair, bilateral):
    """The side pressed 1 µm in (the sphere by its radius less 1 µm): g_N = −1 µm on
    both routes (on the curve, 0), and both timed."""
    row = pair_cost.measure(pair, bilateral, batch=5, rounds=1)
    assert row["fused"] is not None
    assert row["g_N"] == pytest.approx(0.0 if bilateral else -pair_cost.PRESS, abs=1e-9)
    assert row["compiled_us"] > 0.0 and row["python_us"] > 0.0 and row["ratio"] > 0.0
