"""LIBERO's side of the project: what runs in LIBERO's own environment (`.venv-libero`, which
`make setup` builds), importing numpy and LIBERO only — the server `sim=libero` steps
(`server`, run by eval/sims/libero.py) and the reference checks' commands (`reference`). Run from
the repository's root as `.venv-libero/bin/python -m eval.sims.libero_env.<module>`; the project's
own environment imports them too, for what both sides share (the frame protocol, the BDDL problems,
`model_arrays`).
"""
