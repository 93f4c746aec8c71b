"""Every file name a product of this project holds, declared once: a dataset (LeRobot v3.0's own
files and our records beside them), a plan, an exam, a LeRobot v2.1 export, an exam's report.
Writers, readers, the checks on what `overwrite=true` may replace and the push all name files
from here.
"""

from __future__ import annotations

# A LeRobot v3.0 dataset: lerobot's own layout (many episodes per chunked file).
CHUNK_FILE = "chunk-{chunk_index:03d}/file-{file_index:03d}"
INFO_PATH = "meta/info.json"
STATS_PATH = "meta/stats.json"
TASKS_PATH = "meta/tasks.parquet"
EPISODES_DIR = "meta/episodes"
EPISODES_PATH = f"{EPISODES_DIR}/" + CHUNK_FILE.format(chunk_index=0, file_index=0) + ".parquet"
DATA_PATH = "data/" + CHUNK_FILE + ".parquet"
VIDEO_PATH = "videos/{video_key}/" + CHUNK_FILE + ".mp4"

# Our records in a dataset or a plan (`plan_only=true`).
SCENES_PATH = "meta/scenes.parquet"  # one row per episode: everything that rebuilds its scene
AUDIT_PATH = "meta/audit.json"  # the confound audit of the plan and of what was written
GENERATION_PATH = "meta/generation.json"  # written last: its presence marks a dataset complete
CARD_PATH = "README.md"  # the dataset (or exam) card, with the hub's front matter
PREVIEW_PATH = "preview.png"  # the contact sheet the card shows
DATASET_ENTRIES = {"meta", "data", "videos", CARD_PATH, PREVIEW_PATH, "images"}  # a dataset folder's own names

# An exam (core/exam.py): the policy's side, the scorer's side, the header.
EXAM_PATH = "exam.json"
TRIALS_FILE, ANSWERS_FILE = "trials.parquet", "answers.parquet"
EXAM_ENTRIES = {EXAM_PATH, TRIALS_FILE, ANSWERS_FILE, CARD_PATH}  # an exam folder's own names

# A LeRobot v2.1 export (gen/export.py): one file per episode and camera.
V21_DATA_PATH = "data/chunk-{episode_chunk:03d}/episode_{episode_index:06d}.parquet"
V21_VIDEO_PATH = "videos/chunk-{episode_chunk:03d}/{video_key}/episode_{episode_index:06d}.mp4"
EXPORT_ENTRIES = {"meta", "data", "videos"}  # a v2.1 export's own names

PRODUCT_ENTRIES = {"dataset": DATASET_ENTRIES, "plan": DATASET_ENTRIES, "exam": EXAM_ENTRIES, "export": EXPORT_ENTRIES}
PRODUCTS = tuple(PRODUCT_ENTRIES)  # what this project writes and `overwrite=true` may replace

# An exam's report (python -m eval, python -m eval.score): all a take ever replaces in its `out`.
REPORTS = ("report.json", "report.md", "report.html")
ROLLOUTS = "rollouts.parquet"  # the rollout logs the scorer reads
