"""The benchmark's observed convergence order on synthetic ladders with a known law."""
import pytest

from compare.workflows.bench import ORDERS, _fixed_dt
from compare.workflows.work_precision import convergence_orders


def ladder(law, steps=(8e-3, 4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4, 6.25e-5)):
    return [{"solver": "s", "method": "rk4", "settings": {"dt": h}, "rel_error": law(h)}
            for h in steps]


@pytest.mark.parametrize("order", [1, 2, 4])
def test_order_of_a_power_law(order):
    """error = C·h^p: the observed order is p (to round-off)."""
    (o,) = convergence_orders(ladder(lambda h: 0.3 * (h / 8e-3) ** order * 1e-3), 1e-13,
                              _fixed_dt, lambda r: ORDERS[r["method"]])
    assert o["observed"] == pytest.approx(order, abs=1e-9)
    assert o["flag"] == (order < 4 - 0.5)


def test_a_model_floor_is_not_read_as_a_low_order():
    """error = C·h² + floor (e.g. lagrange-partial's finite differences, 2.6e-5): the order is
    read from error − floor on the rungs above 3 × floor, so it is 2, not the ~0 slope of the
    plateau. The floor is estimated by the finest rung's error, which still holds C·h² (3e-7
    here): the slope is 2.0018; window 0.01."""
    (o,) = convergence_orders(ladder(lambda h: 5e-3 * (h / 8e-3) ** 2 + 2.6e-5), 1e-13,
                              _fixed_dt, lambda r: 2)
    assert o["observed"] == pytest.approx(2.0, abs=0.01)
    assert not o["flag"]
