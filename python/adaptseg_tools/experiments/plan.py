"""A part of scripts/results.toml expanded into what to do: per stage, the folders to remove, the
jobs (each one or more commands run in order), the tables to print after them.

The keys of a part (scripts/results.toml's header says what each means): description, like,
parts, knobs, let, setup, requires, for, remove, make, parallel, runs, tables.
"""

from __future__ import annotations

import contextlib
import copy
import glob
import os
import shlex
from dataclasses import dataclass, field
from typing import Any, Iterator, Mapping

from adaptseg_tools.experiments import steps
from adaptseg_tools.experiments.templates import Scope, TemplateError, Words

PART_KEYS = {"description", "like", "parts", "knobs", "let", "setup", "requires", "for", "remove", "make",
             "parallel", "runs", "tables"}
# A group of runs: its matrix, and one command (these keys) or a chain of them (`commands`).
MATRIX_KEYS = {"for", "folds", "let", "if_exists", "commands"}
COMMAND_KEYS = {"config", "name", "program", "args", "log", "stdout", "stderr", "check"}
TABLE_KEYS = {"for", "text", "command", "stdin", "if_exists", "if_missing"}
REQUIRE_KEYS = {"for", "path", "part", "hint"}


class CatalogError(ValueError):
    """scripts/results.toml says something the driver cannot do; the message says where."""


@dataclass
class Command:
    """One program run: its output to `log` (stdout and stderr), or to `stdout` and `stderr`."""

    argv: list[str]
    log: str | None = None
    stdout: str | None = None
    stderr: str | None = None
    check: str | None = None  # a file the run must have written, not empty
    what: str | None = None  # the run in a failure message
    folder: str | None = None  # the folder it writes (an adaptseg_evaluate run's --out)

    def shell(self) -> str:
        """The command as a shell would run it, redirections included."""
        line = shlex.join(self.argv)
        if self.log:
            return f"{line} > {shlex.quote(self.log)} 2>&1"
        if self.stdout:
            line += f" > {shlex.quote(self.stdout)}"
        if self.stderr:
            line += f" 2> {shlex.quote(self.stderr)}"
        return line


@dataclass
class Table:
    """A line of text, or a command whose output is printed; its globs are expanded when it runs."""

    text: str | None = None
    words: list[str] = field(default_factory=list)
    stdin: str | None = None  # a glob: the files, concatenated, are the command's input


@dataclass
class Stage:
    """One part's removals, runs and tables (a part with `for` has one stage per item)."""

    part: str
    root: str
    remove: list[str]
    make: list[str]
    jobs: list[list[Command]]
    parallel: bool
    tables: list[Table]


@dataclass
class Plan:
    stages: list[Stage]
    missing: list[str]  # what the part needs and is not there, each with how to make it


@contextlib.contextmanager
def place(where: str) -> Iterator[None]:
    """Says `where` (the part, the entry) in the message of an error of the catalogue."""
    try:
        yield
    except CatalogError:
        raise
    except TemplateError as e:
        raise CatalogError(f"{where}: {e}") from None
    except KeyError as e:
        raise CatalogError(f"{where}: missing key {e}") from None


def check_keys(entry: Any, known: set[str], where: str) -> None:
    if not isinstance(entry, dict):
        raise CatalogError(f"{where}: a table expected, not {entry!r}")
    unknown = set(entry) - known
    if unknown:
        raise CatalogError(f"{where}: unknown key {', '.join(sorted(unknown))} (known: {', '.join(sorted(known))})")


def part_spec(catalog: Mapping[str, Any], name: str, seen: tuple[str, ...] = ()) -> dict:
    """The part as written, a `like` part on top of the part it is like (knobs and let merged)."""
    parts = catalog["parts"]
    if name not in parts:
        raise CatalogError(f"unknown part '{name}'; the parts: {', '.join(parts)}")
    if name in seen:
        raise CatalogError(f"parts.{name}: like itself, through {' -> '.join(seen)}")
    spec = copy.deepcopy(parts[name])
    check_keys(spec, PART_KEYS, f"parts.{name}")
    if "parts" in spec:
        check_keys(spec, {"description", "parts"}, f"parts.{name} (a part of parts)")
    if "like" in spec:
        base = part_spec(catalog, spec.pop("like"), seen + (name,))
        for key in ("knobs", "let"):
            spec[key] = {**base.get(key, {}), **spec.get(key, {})}
        spec = {**base, **spec}
    return spec


def present(path: str) -> bool:
    """A folder, a file that is not empty, or (a glob) anything that matches."""
    if glob.has_magic(path):
        return bool(glob.glob(path))
    return os.path.isdir(path) or (os.path.isfile(path) and os.path.getsize(path) > 0)


def expand(catalog: Mapping[str, Any], name: str, env: Mapping[str, str], jobs: int) -> Plan:
    """Part `name` with the knobs of `env` (an unset or empty knob takes its default) and
    `jobs` runs at a time."""
    spec = part_spec(catalog, name)
    if "parts" in spec:
        plans = [expand(catalog, sub, env, jobs) for sub in spec["parts"]]
        return Plan([s for p in plans for s in p.stages], [m for p in plans for m in p.missing])
    top = Scope({**catalog.get("values", {}), "jobs": Words((str(jobs),)), "part": Words((name,))})
    knobs = {}
    for knob, default in spec.get("knobs", {}).items():
        given = env.get(knob, "")
        knobs[knob] = (Words(tuple(given.split())) if isinstance(default, list) else Words((given,))) if given else default
    scope = top.child(knobs).child(spec.get("let", {}))
    with place(f"parts.{name}"):
        if "setup" in spec:
            scope = scope.child(steps.run(spec["setup"], scope))
        missing = list(missing_requirements(spec, scope, name))
        body = list(scope.loop(spec["for"])) if "for" in spec else [scope]
        stages = [stage(catalog, spec, s, name) for s in body]
    return Plan(stages, missing)


def missing_requirements(spec: dict, scope: Scope, name: str) -> Iterator[str]:
    for i, entry in enumerate(spec.get("requires", [])):
        check_keys(entry, REQUIRE_KEYS, f"parts.{name}.requires[{i}]")
        for s in scope.loop(entry.get("for", {})):
            path = s.word(entry["path"])
            if not present(path):
                how = s.text(entry["hint"]) if "hint" in entry else f"run 'bash scripts/results.sh {entry['part']}' first"
                yield f"{name} needs {path}: {how}"


def stage(catalog: Mapping[str, Any], spec: dict, scope: Scope, name: str) -> Stage:
    root = scope.word("{root}")  # the results' folder: every run's is under it
    jobs: list[list[Command]] = []
    for i, group in enumerate(spec.get("runs", [])):
        where = f"parts.{name}.runs[{i}]"
        check_keys(group, MATRIX_KEYS | COMMAND_KEYS, where)
        if "commands" in group and COMMAND_KEYS & set(group):
            raise CatalogError(f"{where}: {', '.join(sorted(COMMAND_KEYS & set(group)))} belong in its commands")
        chain = group.get("commands", [group])
        for j, command in enumerate(chain):
            check_keys(command, COMMAND_KEYS | (MATRIX_KEYS if command is group else set()), f"{where}.commands[{j}]")
        with place(where):
            jobs += [[make_command(s, c, root) for c in chain] for s in run_scopes(catalog, group, scope)]
    tables = []
    for i, entry in enumerate(spec.get("tables", [])):
        check_keys(entry, TABLE_KEYS, f"parts.{name}.tables[{i}]")
        with place(f"parts.{name}.tables[{i}]"):
            tables += list(make_tables(entry, scope))
    with place(f"parts.{name}"):
        remove = [p for entry in spec.get("remove", []) for p in entry_words(scope, entry)]
        make = [p for entry in spec.get("make", []) for p in entry_words(scope, entry)]
    for path in remove:
        if not path.startswith(root + "/"):
            raise CatalogError(f"parts.{name}.remove: {path} is not under {root}/; the driver removes nothing else")
    return Stage(name, root, remove, make, jobs, spec.get("parallel", True), tables)


def entry_words(scope: Scope, entry: Any) -> list[str]:
    """A removal or folder entry: a template's words, or `{ for = ..., path = ... }`."""
    if isinstance(entry, dict):
        return [w for s in scope.loop(entry.get("for", {})) for w in s.words(entry["path"])]
    return scope.words(entry)


def run_scopes(catalog: Mapping[str, Any], group: dict, scope: Scope) -> Iterator[Scope]:
    """The scope of each run of a group: its `for` (outermost), then each fold set's runs, then
    its `let`; only those whose `if_exists` path is there."""
    folds = catalog.get("folds", {})
    for outer in scope.loop(group.get("for", {})):
        names = outer.evaluate(group["folds"]) if "folds" in group else [None]
        for fold in names:
            if fold is not None and fold not in folds:
                raise CatalogError(f"unknown fold set '{fold}'; the fold sets: {', '.join(folds)}")
            spec = folds.get(fold, {})
            values = {k: v for k, v in spec.items() if k != "for"}
            for inner in outer.child(values).loop(spec.get("for", {})):
                run = inner.child(group.get("let", {}))
                if "if_exists" not in group or present(run.word(group["if_exists"])):
                    yield run


def make_command(scope: Scope, spec: dict, root: str) -> Command:
    """A command of a run. With `config`, an adaptseg_evaluate run (unless `program` says
    otherwise): --out {root}/CONFIG/NAME, its log NAME.log beside it, and it must write
    results.csv there."""
    if "config" in spec:
        config, name = scope.word(spec["config"]), scope.word(spec.get("name", "{name}"))
        out = f"{root}/{config}/{name}"
        argv = scope.words(spec.get("program", "{evaluate}")) + scope.words(spec.get("args", "")) + ["--out", out]
        return Command(argv, log=out + ".log", check=out + "/results.csv", what=f"{config}/{name}", folder=out)
    optional = {key: scope.word(spec[key]) for key in ("log", "stdout", "stderr", "check") if key in spec}
    command = Command(scope.words(spec["program"]) + scope.words(spec.get("args", "")), **optional)
    command.what = command.check
    return command


def make_tables(entry: dict, scope: Scope) -> Iterator[Table]:
    commands = entry.get("command", [])
    for s in scope.loop(entry.get("for", {})):
        if "if_exists" in entry and not present(s.word(entry["if_exists"])):
            continue
        if "if_missing" in entry and present(s.word(entry["if_missing"])):
            continue
        if "text" in entry:
            yield Table(text=s.text(entry["text"]))
        for command in [commands] if isinstance(commands, str) else commands:
            yield Table(words=s.words(command), stdin=s.word(entry["stdin"]) if "stdin" in entry else None)
