"""The objects our LIBERO worlds drew least like LIBERO, close up: LIBERO's own frame, ours at an
earlier revision, ours now in the fast look and in the full look (`look=full`, core/spec.py), side
by side, each with its mean absolute difference from LIBERO's inside the object's own pixels (the
docs/LIBERO.md's picture, docs/libero_objects_side_by_side.png):
`python scripts/libero_objects_side_by_side.py [before=4a9eaf0] [out=docs/libero_objects_side_by_side.png]`.

`before` is a git revision: its tree is exported to a temporary folder and this script renders our
frames there (`python <copy of this script> frames <request> <theirs> <out>`, which uses only what
both revisions have: scene_for, load_state in either form, Cameras.render).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent

# (world, task, state, camera, thing): the worst object or fixture of each world at LIBERO's states
# (the picture tests' figures), in the camera where it was worst
SHOWN = (
    ("libero_object", 0, 0, "image", "salad_dressing_1"),
    ("libero_object", 1, 0, "image2", "basket_1"),
    ("libero_spatial", 0, 0, "image", "flat_stove_1"),
    ("libero_spatial", 0, 1, "image2", "akita_black_bowl_1"),
    ("libero_goal", 1, 0, "image", "flat_stove_1"),
)


@dataclass
class ObjectsOptions:
    before: str = "4a9eaf0"  # the git revision whose frames are "ours before"
    out: str = "docs/libero_objects_side_by_side.png"


def liberos_frames(world: str, cases: list[list[int]], out: Path) -> Path:
    """LIBERO's own `render` of a suite's (task, state) cases, in `.venv-libero` (eval/sims/libero_env/reference.py)."""
    from core.profiles import LIBERO

    request = out.with_suffix(".json")
    request.write_text(json.dumps({"suite": world, "size": LIBERO.image_size, "cases": cases}))
    from eval.sims.libero import in_liberos

    subprocess.run(in_liberos("reference", "render", str(request), str(out)), cwd=ROOT, check=True, capture_output=True)
    return out


def our_frames(
    world_name: str, cases: list[list[int]], theirs: np.lib.npyio.NpzFile, labels: bool = True, look: str | None = None
) -> dict:
    """Our frames of both cameras (`<task>-<state>-<camera>`) at LIBERO's states, the fixtures posed
    as LIBERO drew them, and (`labels`) what each pixel shows (`-labels`); drawn with `look`, or as
    a revision before looks drew them (None)."""
    from core import libero, worlds
    from core.profiles import LIBERO
    from gen.planning.plan import default_setup
    from oracle.render import Cameras
    from oracle.scene import scene_for
    from referents import registry

    world, referent = worlds.world(world_name), registry.load(world_name)
    scene = scene_for(referent.assets(), "libero", world.name, *([look] if look else []))
    cameras, out = Cameras(scene, LIBERO.image_size, LIBERO.camera_names), {}
    for task, state in cases:
        for name, *pose in theirs[f"{task}-{state}-fixtures"].tolist():  # LIBERO draws these at each reset
            body = scene.model.body(f"{name}_main").id
            scene.model.body_pos[body], scene.model.body_quat[body] = pose[:3], pose[3:]
        _load(scene, referent, world, libero.tasks(world.suite)[task], state, default_setup(referent))
        out |= {f"{task}-{state}-{c}": f.copy() for c, f in cameras.render().items()}
        if labels:
            out |= {f"{task}-{state}-{c}-labels": f for c, f in cameras.labels().items()}
    cameras.close()
    return out


def _load(scene, referent, world, task: str, state: int, setup) -> None:  # noqa: ANN001
    """gen.canonical's load_state as the running revision has it: of a suite (now), or of a
    referent and a world (revisions before LIBERO-PRO's suites)."""
    import inspect

    from gen.products import canonical

    if "suite" in inspect.signature(canonical.load_state).parameters:
        suite = canonical.suite_of(canonical.CanonicalOptions(world=world.name))
        canonical.load_state(scene, suite, task, state, setup)
    else:
        canonical.load_state(scene, referent, world, task, state, setup)


def _before(revision: str, world: str, cases: list[list[int]], theirs: Path, tmp: Path) -> dict:
    """Our frames as the revision `revision` renders them: this script, run in that revision's tree."""
    tree = tmp / "before"
    tree.mkdir(exist_ok=True)
    if not (tree / "oracle").is_dir():
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", revision], check=True, capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", str(tree)], input=archive, check=True)
        shutil.copy(__file__, tree / "scripts" / Path(__file__).name)
    request, out = tmp / f"{world}-before.json", tmp / f"{world}-before.npz"
    request.write_text(json.dumps({"world": world, "cases": cases}))
    script = tree / "scripts" / Path(__file__).name
    env = {**os.environ, "PYTHONPATH": str(tree)}  # that revision's packages, not this checkout's
    subprocess.run([sys.executable, str(script), "frames", str(request), str(theirs), str(out)], check=True, cwd=tree, env=env)
    return dict(np.load(out))


def picture(options: ObjectsOptions) -> None:
    from PIL import Image, ImageDraw

    from core.profiles import LIBERO
    from core.spec import LOOKS
    from eval.sims.libero_env.reference import named, object_differences

    rows = []
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        for world in dict.fromkeys(w for w, *_ in SHOWN):
            cases = [[t, s] for w, t, s, *_ in SHOWN if w == world]
            theirs_file = liberos_frames(world, cases, tmp / f"{world}-theirs.npz")
            theirs = np.load(theirs_file, allow_pickle=True)
            now, full = (our_frames(world, cases, theirs, look=look) for look in LOOKS)
            before = _before(options.before, world, cases, theirs_file, tmp)
            for w, t, s, camera, thing in SHOWN:
                if w != world:
                    continue
                key = f"{t}-{s}-{LIBERO.cameras[camera]}"
                reference = theirs[key][::-1, ::-1]  # as a policy sees it (lerobot's LiberoProcessorStep)
                their_labels = named(theirs[f"{key}-labels"][::-1, ::-1], theirs[f"{t}-{s}-things"])
                ours = [before[f"{t}-{s}-{camera}"], now[f"{t}-{s}-{camera}"], full[f"{t}-{s}-{camera}"]]
                labels = [now[f"{t}-{s}-{camera}-labels"]] * 2 + [full[f"{t}-{s}-{camera}-labels"]]  # before: as now
                figures = [object_differences(o, reference, lab, their_labels)[thing] for o, lab in zip(ours, labels)]
                ys, xs = np.nonzero(their_labels == thing)
                box = (slice(max(ys.min() - 6, 0), ys.max() + 7), slice(max(xs.min() - 6, 0), xs.max() + 7))
                rows.append(
                    (
                        f"{world} task {t} state {s}, {LIBERO.cameras[camera]}: {thing}",
                        figures,
                        [reference[box], *(o[box] for o in ours)],
                    )
                )
    height, width = 192, 4 * 206
    sheet = Image.new("RGB", (width, len(rows) * (height + 44)), "white")
    draw = ImageDraw.Draw(sheet)
    for i, (title, (before, now, full), crops) in enumerate(rows):
        y = i * (height + 44)
        draw.text((4, y + 4), title, fill="black")
        captions = ("LIBERO's", f"ours before: {before:.1f}/255", f"fast look: {now:.1f}/255", f"look=full: {full:.1f}/255")
        for j, (crop, caption) in enumerate(zip(crops, captions)):
            scale = min(height / crop.shape[0], 192 / crop.shape[1])
            image = Image.fromarray(crop).resize((round(crop.shape[1] * scale), round(crop.shape[0] * scale)), Image.NEAREST)
            sheet.paste(image, (j * 206, y + 18))
            draw.text((j * 206 + 2, y + 18 + height + 4), caption, fill="black")
    sheet.save(options.out)
    print(f"wrote {options.out}")


def _frames(request_file: str, theirs_file: str, out: str) -> None:
    """The `frames` command: our frames only (a revision before Cameras.labels), written to `out` (.npz)."""
    request = json.loads(Path(request_file).read_text())
    theirs = np.load(theirs_file, allow_pickle=True)
    np.savez(out, **our_frames(request["world"], request["cases"], theirs, labels=False))


if __name__ == "__main__":
    if sys.argv[1:2] == ["frames"]:
        _frames(*sys.argv[2:5])
        sys.exit(0)
    from jobs.cli import main

    sys.exit(main("python scripts/libero_objects_side_by_side.py", ObjectsOptions, picture, doc=__doc__))
