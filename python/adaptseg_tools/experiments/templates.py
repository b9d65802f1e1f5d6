"""The values of scripts/results.toml and their templates.

A value is a string (a template: split into words as the shell splits them, quotes kept
together), a list (one word per item), already-made `Words` (a knob from the environment, a
loop's item) or one of four computed kinds, tables with these keys:

  { for = {...}, words = "T" }        T's words once per item of the loop, one after another
  { items = "T", except = "U" }       T's words less U's
  { join = ",", items = "T" }         T's words as one, joined (`sort = true`: sorted first)
  { lookup = "T", table = {...}, default = V }   the entry named by T's text, else V

`{name}` refers to a value. A word that is exactly `{name}` becomes all of that value's words
(none, one or many); inside a longer word, a value must be exactly one word. Every value is
evaluated in the scope where it is used, the innermost: a value of the catalogue may refer to a
loop's variable (`train` to `train_tiles`, `train_tiles` to `tile`).

A loop (`for = { name = ..., ... }`, first name outermost) runs over a value's words, or over a
list of tables (each sets several names at once: `{ tile = "4", other = "6" }`).
"""

from __future__ import annotations

import re
import shlex
from dataclasses import dataclass
from typing import Any, Iterator, Mapping

REF = re.compile(r"\{([A-Za-z_][A-Za-z0-9_-]*)\}")


class TemplateError(ValueError):
    """A value that cannot be evaluated: an unknown name, a cycle, a list inside a word."""


@dataclass(frozen=True)
class Words:
    """Words taken as they are, never as a template (the environment's, a loop item's)."""

    words: tuple[str, ...]


class Scope:
    """Names and their values, inside an outer scope (the catalogue, the part, a run's loop)."""

    def __init__(self, values: Mapping[str, Any], outer: Scope | None = None):
        self.values = dict(values)
        self.outer = outer
        self._evaluating: list[str] = []

    def child(self, values: Mapping[str, Any]) -> Scope:
        return Scope(values, self)

    def raw(self, name: str) -> Any:
        """The value of `name` as written, from the innermost scope that has it."""
        scope: Scope | None = self
        while scope is not None:
            if name in scope.values:
                return scope.values[name]
            scope = scope.outer
        raise TemplateError(f"unknown name {{{name}}}")

    def value(self, name: str) -> list[str]:
        """The words of `name`, evaluated here."""
        if name in self._evaluating:
            raise TemplateError("values that refer to each other: " + " -> ".join(self._evaluating + [name]))
        raw = self.raw(name)
        self._evaluating.append(name)
        try:
            return self.evaluate(raw)
        except TemplateError as e:
            raise TemplateError(f"in {{{name}}}: {e}") from None
        finally:
            self._evaluating.pop()

    def evaluate(self, value: Any) -> list[str]:
        """The words of a value as written (a template, a list, Words or a computed kind)."""
        if isinstance(value, Words):
            return list(value.words)
        if isinstance(value, str):
            return self.words(value)
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return [str(value)]
        if isinstance(value, list):
            out: list[str] = []
            for item in value:
                if isinstance(item, dict):
                    raise TemplateError("a list of tables is a loop's items: use it in `for` only")
                out += self.words_of_item(str(item))
            return out
        if isinstance(value, dict):
            return self.computed(value)
        raise TemplateError(f"a value must be a string, a list or a table, not {value!r}")

    def computed(self, value: dict) -> list[str]:
        """One of the computed kinds (this module's docstring)."""
        keys = set(value)
        if keys == {"for", "words"}:
            return [w for scope in self.loop(value["for"]) for w in scope.words(value["words"])]
        if keys == {"items", "except"}:
            dropped = set(self.evaluate(value["except"]))
            return [w for w in self.evaluate(value["items"]) if w not in dropped]
        if keys in ({"join", "items"}, {"join", "items", "sort"}):
            items = self.evaluate(value["items"])
            return [str(value["join"]).join(sorted(items) if value.get("sort") else items)]
        if keys in ({"lookup", "table"}, {"lookup", "table", "default"}):
            key = self.text(value["lookup"])
            if key in value["table"]:
                return self.evaluate(value["table"][key])
            if "default" not in value:
                raise TemplateError(f"lookup: no entry {key!r} (entries: {', '.join(value['table'])}) and no default")
            return self.evaluate(value["default"])
        raise TemplateError(f"a table value needs the keys of one kind (for+words, items+except, join+items, "
                            f"lookup+table[+default]), not {', '.join(sorted(keys))}")

    def words_of_item(self, item: str) -> list[str]:
        """One word as written, or all the words of the value it names (`{name}` alone)."""
        m = REF.fullmatch(item)
        return self.value(m.group(1)) if m else [self.word(item)]

    def words(self, template: str) -> list[str]:
        """A template's words: split as the shell splits, then each word's `{name}`s replaced."""
        try:
            parts = shlex.split(template)
        except ValueError as e:
            raise TemplateError(f"cannot split {template!r}: {e}") from None
        return [w for part in parts for w in self.words_of_item(part)]

    def word(self, template: str) -> str:
        """One word: each `{name}` in it replaced by that value's single word."""
        def one(m: re.Match) -> str:
            words = self.value(m.group(1))
            if len(words) != 1:
                raise TemplateError(f"{{{m.group(1)}}} is {len(words)} words ({' '.join(words)!r}) inside the word "
                                    f"{template!r}: there it must be exactly one (a list goes alone, or in a `for`)")
            return words[0]
        return REF.sub(one, template)

    def text(self, template: str) -> str:
        """Text (a heading, a message): each `{name}` replaced by its words joined by blanks."""
        return REF.sub(lambda m: " ".join(self.value(m.group(1))), template)

    def loop_items(self, over: Any) -> list[Any]:
        """A loop's items: words, or the tables of a list of tables (directly or by its name)."""
        if isinstance(over, str) and REF.fullmatch(over):
            raw = self.raw(REF.fullmatch(over).group(1))
            if isinstance(raw, list) and any(isinstance(item, dict) for item in raw):
                return raw
        if isinstance(over, list):
            return [item for x in over for item in ([x] if isinstance(x, dict) else self.words_of_item(str(x)))]
        return self.evaluate(over)

    def loop(self, spec: Mapping[str, Any]) -> Iterator[Scope]:
        """One scope per combination of the loop's items, the first name outermost."""
        names = list(spec)

        def nest(i: int, scope: Scope) -> Iterator[Scope]:
            if i == len(names):
                yield scope
                return
            for item in scope.loop_items(spec[names[i]]):
                values = item if isinstance(item, dict) else {names[i]: Words((item,))}
                yield from nest(i + 1, scope.child(values))

        yield from nest(0, self)
