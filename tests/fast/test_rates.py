"""The paired difference of two takes of one exam: trials resampled for both at once."""

from core.rates import cluster_ci, paired_difference


def test_a_paired_difference_is_tighter_than_the_two_intervals_and_sees_a_shift_they_miss() -> None:
    # 20 trials of 5 rows; the second take succeeds on one more row of each trial than the first,
    # while trials differ widely in how hard they are (the shared scene)
    trials = [t for t in range(20) for _ in range(5)]
    first = [float(i < t % 5) for t in range(20) for i in range(5)]
    second = [float(i < t % 5 + 1) for t in range(20) for i in range(5)]
    diff = paired_difference(first, second, trials)
    assert diff["difference"] == 0.2 and diff["n"] == 100
    assert diff["ci_trials"] == [0.2, 0.2]  # every trial gains exactly one row: no doubt left
    assert cluster_ci(second, trials)[0] < cluster_ci(first, trials)[1]  # apart, the two intervals overlap
    same = paired_difference(first, first, trials)
    assert same["difference"] == 0.0 and same["ci_trials"] == [0.0, 0.0]
    mixed = paired_difference(first, [1.0 - v for v in first], trials)
    assert mixed["ci_trials"][0] < mixed["difference"] < mixed["ci_trials"][1]
