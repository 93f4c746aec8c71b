"""Where a take's rollouts run: the runner and our simulator (`rollout`), LIBERO's simulator
(`libero`, its other side in `libero_env`), and the rollout log both sides write and the scorer
reads (`log`). Imports nothing itself, so LIBERO's environment may import `libero_env` through it.
"""
