"""What a policy's predicted point may be: a point [column, row] anywhere (an object at the frame's
edge has its centre outside it), or a heat map over the frame; nothing else."""

import numpy as np

from eval.sims.rollout import check_prediction


def test_a_point_off_the_frame_is_a_prediction_and_a_broken_one_is_named() -> None:
    assert check_prediction([64.58, 21.0], 64) == ([64.58, 21.0], None)  # the oracle's cabinet bowl, at 64 px
    heat = np.zeros((8, 8))
    heat[2, 5] = 1.0
    assert check_prediction(heat, 8) == ([5.5, 2.5], None)
    assert check_prediction([float("nan"), 1.0], 64) == (None, "prediction [nan, 1.0] is not a finite point")
    point, error = check_prediction([1.0, 2.0, 3.0], 64)
    assert point is None and error.startswith("prediction has shape (3,): expected a point [column, row] (2,)")
