"""Runs a plan (adaptseg_tools.experiments.plan), or prints its commands (a dry run).

Per stage: the folders removed, the jobs run at most JOBS at a time (each job's commands one
after another, each command's output in its log), every run checked for what it must write
("FAILED: ... (see ...log)", exit 1), then the tables printed.
"""

from __future__ import annotations

import fnmatch
import glob
import os
import shlex
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from contextlib import ExitStack
from pathlib import Path
from typing import BinaryIO, Callable, TextIO

from adaptseg_tools.experiments.plan import Command, Plan, Stage, Table


def expand_globs(words: list[str], matches: Callable[[str], list[str]]) -> list[str]:
    """A table's words with their globs expanded as the shell would (`matches`: a glob's sorted
    matches). NAME=GLOB (the form of sweep_table's configurations) becomes NAME= and the
    matching folders joined by commas, and is left out where nothing matches; a plain GLOB that
    matches nothing stays as it is."""
    out: list[str] = []
    for word in words:
        label, eq, pattern = word.partition("=")
        if eq and glob.has_magic(pattern) and not glob.has_magic(label):
            found = matches(pattern)
            if found:
                out.append(label + "=" + ",".join(m.rstrip("/") for m in found))
        elif glob.has_magic(word):
            out += matches(word) or [word]
        else:
            out.append(word)
    return out


def real_matches(pattern: str) -> list[str]:
    return sorted(glob.glob(pattern))


class DryFiles:
    """The files as a dry run takes them to be: those there, less what the stages before
    removed, plus what their runs would write (their folders, logs and checked files)."""

    def __init__(self) -> None:
        self.removed: list[str] = []
        self.planned: dict[str, bool] = {}  # path -> is a folder

    def gone(self, path: str) -> bool:
        path = path.rstrip("/")
        return any(path == r or path.startswith(r + "/") for r in self.removed)

    def remove(self, pattern: str) -> None:
        for path in self.matches(pattern) or [pattern]:
            self.removed.append(path.rstrip("/"))
        self.planned = {p: d for p, d in self.planned.items() if not self.gone(p)}

    def write(self, command: Command) -> None:
        files = [f for f in (command.log, command.stdout, command.stderr, command.check) if f and f != os.devnull]
        folders = [f.rsplit("/", 1)[0] for f in files if "/" in f] + ([command.folder] if command.folder else [])
        for path, folder in [(f, False) for f in files] + [(f, True) for f in folders]:
            parts = path.split("/")
            for i in range(1, len(parts)):
                self.planned["/".join(parts[:i])] = True
            self.planned[path] = folder
        self.removed = [r for r in self.removed if not any(p == r or p.startswith(r + "/") for p in files + folders)]

    def matches(self, pattern: str) -> list[str]:
        folders_only = pattern.endswith("/")
        segments = pattern.rstrip("/").split("/")
        found = {p for p in glob.glob(pattern) if not self.gone(p)}
        for path, folder in self.planned.items():
            names = path.split("/")
            if (folder or not folders_only) and len(names) == len(segments) and \
                    all(fnmatch.fnmatchcase(n, s) for n, s in zip(names, segments)):
                found.add(path + "/" if folders_only else path)
        return sorted(found)


def remove(pattern: str) -> None:
    """rm -rf PATTERN."""
    for path in glob.glob(pattern) if glob.has_magic(pattern) else [pattern]:
        if os.path.isdir(path) and not os.path.islink(path):
            shutil.rmtree(path)
        elif os.path.lexists(path):
            os.remove(path)


def written(path: str) -> bool:
    return os.path.isfile(path) and os.path.getsize(path) > 0


def open_output(files: ExitStack, path: str | None) -> BinaryIO | None:
    """`path` opened for a command's output (its folder made first), closed with `files`."""
    if path is None:
        return None
    if path != os.devnull:
        os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    return files.enter_context(open(path, "wb"))


def run_job(job: list[Command]) -> str | None:
    """Runs the job's commands in order, up to the first that fails; its failure, if any."""
    for command in job:
        with ExitStack() as files:
            stdout = open_output(files, command.log or command.stdout)
            stderr = subprocess.STDOUT if command.log else open_output(files, command.stderr)
            try:
                code = subprocess.run(command.argv, stdin=subprocess.DEVNULL, stdout=stdout, stderr=stderr).returncode
            except OSError as e:
                return f"FAILED: cannot run {command.argv[0]}: {e.strerror}"
        if command.check and not written(command.check):
            log = command.log or command.stderr
            return f"FAILED: {command.what}" + (f" (see {log})" if log and log != os.devnull else "")
        if code != 0 and not command.check:
            return f"FAILED: {shlex.join(command.argv)} (exit status {code})"
    return None


def run_table(table: Table, dry: DryFiles | None, out: TextIO) -> int:
    """Prints the table's text, or runs its command (its output printed); its exit status. A
    dry run (`dry`: the files it takes to be there) prints the command instead."""
    if table.text is not None:
        if dry is None:
            print(table.text, file=out, flush=True)
        return 0
    matches = dry.matches if dry else real_matches
    argv = expand_globs(table.words, matches)
    inputs = (matches(table.stdin) or [table.stdin]) if table.stdin else []
    if dry:
        print((f"cat {shlex.join(inputs)} | " if inputs else "") + shlex.join(argv), file=out)
        return 0
    out.flush()
    sys.stdout.flush()
    if inputs:
        data = b"".join(Path(path).read_bytes() for path in inputs)
        code = subprocess.run(argv, input=data).returncode
    else:
        code = subprocess.run(argv, stdin=subprocess.DEVNULL).returncode
    if code != 0:
        print(f"results: {shlex.join(argv)} failed (exit status {code})", file=sys.stderr)
    return code


def run_stage(stage: Stage, jobs: int, dry: DryFiles | None, out: TextIO) -> int:
    for pattern in stage.remove:
        if dry:
            print(f"rm -rf {shlex.quote(pattern)}", file=out)
            dry.remove(pattern)
        else:
            remove(pattern)
    if dry:
        for job in stage.jobs:
            for command in job:
                print(command.shell(), file=out)
                dry.write(command)
        if stage.jobs:
            print("wait", file=out)
    else:
        for folder in stage.make:
            os.makedirs(folder, exist_ok=True)
        pool = ThreadPoolExecutor(max_workers=jobs if stage.parallel else 1)
        try:
            failures = [f for f in pool.map(run_job, stage.jobs) if f]
        finally:  # interrupted: start no more jobs
            pool.shutdown(cancel_futures=True)
        if failures:
            print("\n".join(failures), file=sys.stderr)
            return 1
    for table in stage.tables:
        code = run_table(table, dry, out)
        if code != 0:
            return code
    return 0


def run_plan(plan: Plan, jobs: int, dry_run: bool = False, out: TextIO = sys.stdout) -> int:
    """Runs (or prints) every stage; stops at the first that fails. Its exit status."""
    if plan.missing:
        print("\n".join(plan.missing), file=sys.stderr)
        return 1
    dry = DryFiles() if dry_run else None
    for stage in plan.stages:
        code = run_stage(stage, jobs, dry, out)
        if code != 0:
            return code
    return 0
