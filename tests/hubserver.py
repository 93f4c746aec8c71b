"""A small Hugging Face-compatible hub on loopback, for the push tests.

It answers the HTTP endpoints `huggingface_hub` uses to create a dataset repo, upload a folder
in one commit (every file as a regular, inline blob), create and delete tags (creating an
existing one is refused with 409, as the real hub does), create branches, describe a revision
and serve files, and it records every request so tests can check what was sent.
"""

from __future__ import annotations

import base64
import hashlib
import json
import threading
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from urllib.parse import unquote, urlparse


@dataclass
class Repo:
    private: bool
    files: dict[str, bytes] = field(default_factory=dict)
    commits: list[str] = field(default_factory=list)
    refs: dict[str, str] = field(default_factory=dict)  # branch or tag -> commit
    tags: set[str] = field(default_factory=set)
    snapshots: dict[str, dict[str, bytes]] = field(default_factory=dict)  # commit -> files


class Hub:
    def __init__(self) -> None:
        self.repos: dict[str, Repo] = {}
        self.requests: list[dict] = []
        self.fail_commits = 0  # answer this many commits with a 500
        self.server = ThreadingHTTPServer(("127.0.0.1", 0), self._handler())
        self.thread = threading.Thread(target=self.server.serve_forever, daemon=True)

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.server.server_address[1]}"

    def __enter__(self) -> Hub:
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.server.shutdown()

    def _handler(self) -> type[BaseHTTPRequestHandler]:
        hub = self

        class Handler(BaseHTTPRequestHandler):
            def log_message(self, *args: object) -> None:
                pass

            def _reply(self, status: int, body: object = None, headers: dict | None = None, raw: bytes | None = None) -> None:
                data = raw if raw is not None else json.dumps(body if body is not None else {}).encode()
                self.send_response(status)
                self.send_header("Content-Type", "application/json" if raw is None else "application/octet-stream")
                self.send_header("Content-Length", str(len(data)))
                for k, v in (headers or {}).items():
                    self.send_header(k, v)
                self.end_headers()
                if self.command != "HEAD":
                    self.wfile.write(data)

            def _body(self) -> bytes:
                return self.rfile.read(int(self.headers.get("Content-Length", 0)))

            def _record(self, body: bytes = b"") -> None:
                hub.requests.append(
                    {
                        "method": self.command,
                        "path": urlparse(self.path).path,
                        "auth": self.headers.get("Authorization"),
                        "body": body,
                    }
                )

            def do_GET(self) -> None:  # noqa: N802
                self._record()
                self._route()

            do_HEAD = do_GET  # noqa: N815

            def do_POST(self) -> None:  # noqa: N802
                body = self._body()
                self._record(body)
                self._route(body)

            def do_DELETE(self) -> None:  # noqa: N802
                self._record()
                self._route()

            def _route(self, body: bytes = b"") -> None:
                parts = [unquote(p) for p in urlparse(self.path).path.strip("/").split("/")]
                if parts[:2] == ["api", "validate-yaml"]:
                    return self._reply(200, {"errors": [], "warnings": []})
                if parts[:3] == ["api", "repos", "create"]:
                    spec = json.loads(body)
                    repo_id = f"{spec.get('organization') or 'user'}/{spec['name']}"
                    if repo_id in hub.repos:
                        return self._reply(409, {"error": "already exists", "url": f"{hub.url}/datasets/{repo_id}"})
                    hub.repos[repo_id] = Repo(private=bool(spec.get("private")))
                    return self._reply(200, {"url": f"{hub.url}/datasets/{repo_id}", "name": repo_id})
                if parts[0] == "api" and parts[1] == "datasets":
                    repo_id, action, rest = f"{parts[2]}/{parts[3]}", parts[4] if len(parts) > 4 else "", parts[5:]
                    repo = hub.repos.get(repo_id)
                    if repo is None:
                        return self._reply(404, {"error": "Repository not found"}, {"X-Error-Code": "RepoNotFound"})
                    return self._api(repo_id, repo, action, rest, body)
                if parts[0] == "datasets" and len(parts) > 5 and parts[3] == "resolve":
                    repo = hub.repos.get(f"{parts[1]}/{parts[2]}")
                    revision, path = parts[4], "/".join(parts[5:])
                    commit = repo.refs.get(revision, revision) if repo else None
                    files = repo.snapshots.get(commit, {}) if repo else {}
                    if path not in files:
                        return self._reply(404, {"error": "Entry not found"}, {"X-Error-Code": "EntryNotFound"})
                    data = files[path]
                    etag = hashlib.sha1(b"blob %d\0" % len(data) + data).hexdigest()
                    return self._reply(200, raw=data, headers={"X-Repo-Commit": commit, "ETag": f'"{etag}"'})
                self._reply(404, {"error": f"no route {self.path}"})

            def _api(self, repo_id: str, repo: Repo, action: str, rest: list[str], body: bytes) -> None:
                if action == "preupload":
                    files = json.loads(body)["files"]
                    return self._reply(
                        200, {"files": [{"path": f["path"], "uploadMode": "regular", "shouldIgnore": False} for f in files]}
                    )
                if action == "commit":
                    if hub.fail_commits > 0:
                        hub.fail_commits -= 1
                        return self._reply(500, {"error": "storage backend unavailable"})
                    branch = rest[0] if rest else "main"
                    files = dict(repo.snapshots.get(repo.refs.get(branch, ""), {}))
                    for line in body.decode().splitlines():
                        item = json.loads(line)
                        if item["key"] == "file":
                            files[item["value"]["path"]] = base64.b64decode(item["value"]["content"])
                        elif item["key"] == "deletedFile":
                            files.pop(item["value"]["path"], None)
                    sha = hashlib.sha1(
                        json.dumps(sorted((k, hashlib.sha1(v).hexdigest()) for k, v in files.items())).encode()
                    ).hexdigest()
                    repo.snapshots[sha], repo.refs[branch] = files, sha
                    repo.commits.append(sha)
                    repo.files = files
                    return self._reply(200, {"commitUrl": f"{hub.url}/datasets/{repo_id}/commit/{sha}", "commitOid": sha})
                if action == "tag" and self.command == "DELETE":
                    if rest[0] not in repo.tags:
                        return self._reply(404, {"error": "Revision not found"}, {"X-Error-Code": "RevisionNotFound"})
                    repo.tags.discard(rest[0])
                    del repo.refs[rest[0]]
                    return self._reply(200, {})
                if action == "tag":  # POST .../tag/<branch, tag or commit id>
                    tag = json.loads(body)["tag"]
                    if tag in repo.refs:
                        return self._reply(409, {"error": "tag exists"})
                    revision = rest[0] if rest else "main"
                    repo.refs[tag] = repo.refs.get(revision, revision)
                    repo.tags.add(tag)
                    return self._reply(200, {})
                if action == "branch":
                    repo.refs.setdefault(rest[0], repo.refs.get("main", ""))
                    repo.snapshots.setdefault(repo.refs[rest[0]], {})
                    return self._reply(200, {})
                if action == "tree":
                    files = repo.snapshots.get(repo.refs.get(rest[0], rest[0]), {})
                    entries = [
                        {"type": "file", "path": p, "size": len(v), "oid": hashlib.sha1(v).hexdigest()}
                        for p, v in sorted(files.items())
                    ]
                    return self._reply(200, entries)
                if action in ("revision", ""):
                    revision = rest[0] if rest else "main"
                    commit = repo.refs.get(revision, revision)
                    files = repo.snapshots.get(commit, {})
                    info = {
                        "id": repo_id,
                        "sha": commit,
                        "private": repo.private,
                        "siblings": [{"rfilename": p, "size": len(v)} for p, v in sorted(files.items())],
                        "xetEnabled": False,
                        "tags": [],
                    }
                    return self._reply(200, info)
                return self._reply(404, {"error": f"no action {action}"})

        return Handler
