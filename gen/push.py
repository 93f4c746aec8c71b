"""`python -m gen.push <dataset or exam> repo_id=<user/name> [private=true] [branch=<name>]`

Pushes a generated dataset (or exam) to a Hugging Face-compatible hub the way lerobot does:
create the dataset repo, upload the folder in one commit, tag it (`v3.0` for datasets, so
lerobot's loader finds it; `exam-v<format version>` for exams). The endpoint and token come from the usual
HF_ENDPOINT / HF_TOKEN / `huggingface-cli login`. It refuses a dataset that is incomplete or
fails `gen.check`, never prints the token, and when the upload fails says what was and was not
committed: the upload is a single commit, so a retry of the same command is always safe.
"""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING
from urllib.parse import urlparse

from jobs.cli import Failed, UserError, main

if TYPE_CHECKING:
    from huggingface_hub import HfApi

IGNORE = [".*", "**/.*", "*.tmp", "**/*.tmp", "*.partial/**"]


class PushError(RuntimeError):
    pass


def check_repo_id(repo_id: str) -> None:
    if repo_id.count("/") != 1:
        raise PushError(f"repo_id must be <user or org>/<name>, got {repo_id!r}")


@dataclass
class Pushed:
    repo_id: str
    files: list[str]
    commit: str
    tag: str
    url: str


def _files(root: Path) -> list[str]:
    return sorted(
        p.relative_to(root).as_posix()
        for p in root.rglob("*")
        if p.is_file() and not any(part.startswith(".") for part in p.relative_to(root).parts) and p.suffix != ".tmp"
    )


def _validate(root: Path) -> str:
    """The tag to push under, once the folder has passed its integrity checks."""
    if (root / "exam.json").is_file():
        from core.exam import EXAM_VERSION, ExamError, read

        try:
            read(root)
        except ExamError as exc:
            raise PushError(f"refusing to push: {exc}") from None
        return f"exam-v{EXAM_VERSION}"
    from gen.check import Broken, check

    try:
        check(root)
    except Broken as exc:
        raise PushError(f"refusing to push {root}: {exc}") from None
    except (OSError, KeyError, ValueError) as exc:
        raise PushError(f"refusing to push {root}: unreadable ({exc})") from None
    return "v3.0"


def _retag(api: HfApi, repo_id: str, tag: str, commit: str) -> None:
    """Point `tag` at `commit`, moving it if a previous push created it.

    lerobot's loader downloads the `v3.0` revision, so a tag left on an older commit would serve
    the old data without a word. The hub refuses to create an existing tag (409), so it is deleted
    first, as lerobot's own push does. Tagging the commit id rather than the branch means a commit
    landing in between cannot receive the tag.
    """
    from huggingface_hub.errors import HfHubHTTPError

    try:
        api.delete_tag(repo_id, tag=tag, repo_type="dataset")
    except HfHubHTTPError as exc:
        if exc.response is None or exc.response.status_code != 404:  # 404: no such tag yet
            raise
    api.create_tag(repo_id, tag=tag, revision=commit, repo_type="dataset")


def _unreachable(exc: BaseException) -> bool:
    """Whether the hub could not be reached at all (name resolution, a refused or timed-out connection)."""
    import requests

    return isinstance(exc, (requests.exceptions.ConnectionError, requests.exceptions.Timeout))


def push(root: Path, repo_id: str, private: bool = False, branch: str | None = None) -> Pushed:
    from huggingface_hub import HfApi
    from huggingface_hub.errors import HfHubHTTPError

    check_repo_id(repo_id)
    tag = _validate(root)
    files = _files(root)
    api = HfApi(endpoint=os.environ.get("HF_ENDPOINT"))
    size_mb = sum((root / f).stat().st_size for f in files) / 1e6
    stage = "creating the repository"
    try:
        repo = api.create_repo(repo_id, repo_type="dataset", private=private, exist_ok=True)
        if branch:
            stage = f"creating branch {branch}"
            api.create_branch(repo_id, branch=branch, repo_type="dataset", exist_ok=True)
        stage = "uploading"
        commit = api.upload_folder(
            folder_path=root,
            repo_id=repo_id,
            repo_type="dataset",
            revision=branch,
            ignore_patterns=IGNORE,
            commit_message=f"Upload {root.name} ({len(files)} files) with deconfound",
        )
        stage = f"tagging {tag}"
        _retag(api, repo_id, tag, commit.oid)
    except (HfHubHTTPError, OSError, ValueError) as exc:
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        if _unreachable(exc):  # no network, a wrong HF_ENDPOINT: the library's message is a retry object's repr
            reason = f"cannot reach the hub ({urlparse(api.endpoint).netloc})"
        if stage == f"tagging {tag}":
            done = f"all {len(files)} files were committed, but the {tag} tag was not moved to that commit"
        else:
            done = f"nothing was committed ({len(files)} files, {size_mb:.1f} MB pending; the upload is one commit)"
        raise PushError(f"push to {repo_id} failed while {stage}: {reason}; {done}; rerun the same command to retry") from None
    return Pushed(repo_id, files, commit.oid, tag, str(repo))


@dataclass
class PushOptions:
    repo_id: str  # <user or org>/<name> of the hub dataset repo
    root: str = ""  # the dataset or exam folder to push
    private: bool = False  # create the repo private
    branch: str | None = None  # commit to this branch (created if needed) instead of main


def run(options: PushOptions) -> None:
    root = Path(options.root)
    if not root.is_dir():
        raise UserError(f"{root} is not a folder" if root.exists() else f"{root} does not exist")
    try:
        check_repo_id(options.repo_id)
    except PushError as exc:
        raise UserError(str(exc)) from None
    try:
        pushed = push(root, options.repo_id, options.private, options.branch)
    except PushError as exc:
        raise Failed(str(exc)) from None
    print(f"pushed {len(pushed.files)} files to {pushed.url} (commit {pushed.commit[:12]}, tag {pushed.tag})")


if __name__ == "__main__":
    sys.exit(main("python -m gen.push", PushOptions, run, doc=__doc__, positional="root"))
