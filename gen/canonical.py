"""`python -m gen.canonical world=libero_object` (or libero_spatial, libero_goal, or a world of
LIBERO-10's, whose tasks span several: libero_10_living_room takes those set in its living room), or
`suite=<a LIBERO-PRO suite>` (libero_object_swap, libero_spatial_lan, ...): an exam on LIBERO's
own initial states.

Its task rows are exactly a LIBERO suite's tasks: LIBERO's initial states (every one of the 50
per task, or `states=` of them drawn with `seed=`), LIBERO's instructions, the rollout horizon
and settle steps lerobot's LIBERO environment uses. On each state the swap rows are the world's
referent type's (its `canonical` design of the task: in LIBERO-Object every other grocery, in
LIBERO-Spatial the other bowl, named by where it stands), and occ and nonsense rows follow, as
in every exam (core/exam.py). A LIBERO-trained policy's task rate here is its published LIBERO
number; its swap rate is whether it reads the instruction. The `position` policy is the
shortcut LIBERO's layouts reward: it knows the scene and fetches what that task's target was.

A LIBERO-PRO suite perturbs its base suite (objects swapped, moved, recoloured or added; the
instruction paraphrased or another target named) with its own BDDL problems and initial states;
its world is its base suite's. Its scene holds the suite's objects, built from their LIBERO
models (referents/scenery.py), and each task row is given the instruction the suite's BDDL file
writes in its `(:language ...)` line where that differs from the base task's, which is what the
perturbation is (LIBERO-PRO keeps the base task's file name, from which LIBERO's benchmark, and
the runners that use it, take the instruction: they never deliver it); elsewhere the base task's
instruction. `exam.json` records, per task, the file, its language line, the file-name
instruction and the one delivered.

The states are LIBERO's exactly (joints set by name from LIBERO's state vectors), so the first
settle steps show what they show in LIBERO: objects placed slightly into the floor pop up and
settle.
"""

from __future__ import annotations

import sys

from gen.products.canonical import CanonicalOptions, build
from jobs.cli import main

if __name__ == "__main__":
    sys.exit(main("python -m gen.canonical", CanonicalOptions, build, doc=__doc__))
