"""The named steps of scripts/results.toml (a part's `setup = { step = NAME, ... }`): what a
part needs computed from the files there before its runs can be listed, as values.
"""

from __future__ import annotations

import os
from typing import Any, Callable

from adaptseg_tools.experiments.templates import Scope, TemplateError, Words


def stand_in_networks(scope: Scope, loto: str, evaluation: str, evaluation_tiles: list[str]) -> dict[str, Any]:
    """The networks of the leave-one-tile-out stand-in (parts loto-proxy, new-ground-check): every
    Dubai tile with a network of the recipe that never saw it, its leave-one-tile-out network
    `loto`/tile-K where that is bundled (and K is in LOTO_TILES), else, on `evaluation_tiles`,
    the evaluation network. The values: `stand_in`, the tiles in TILES, each a table {tile,
    flier} (the network that flies it); `stand_in_tiles`; `first_flier`, the first tile's
    network; `crossed`, --calibration-network for every leave-one-tile-out network used, then
    the evaluation network."""
    wanted, loto_wanted = set(scope.value("TILES")), set(scope.value("LOTO_TILES"))
    stand_in: list[dict[str, Words]] = []
    crossed: list[str] = []
    for tile in scope.value("tiles"):
        network = f"{loto}/tile-{tile}"
        model = os.path.join(network, "model.onnx")
        if os.path.isfile(model) and os.path.getsize(model) > 0 and tile in loto_wanted:
            crossed += ["--calibration-network", network]
        elif tile in evaluation_tiles:
            network = evaluation
        else:
            continue
        if tile in wanted:
            stand_in.append({"tile": Words((tile,)), "flier": Words((network,))})
    if not stand_in:
        raise TemplateError(f"no tile of TILES ({' '.join(sorted(wanted))}) has a network that never saw it")
    return {
        "stand_in": stand_in,
        "stand_in_tiles": Words(tuple(t["tile"].words[0] for t in stand_in)),
        "first_flier": stand_in[0]["flier"],
        "crossed": Words(tuple(crossed + ["--calibration-network", evaluation])),
    }


STEPS: dict[str, Callable[..., dict[str, Any]]] = {"stand_in_networks": stand_in_networks}


def run(setup: dict[str, Any], scope: Scope) -> dict[str, Any]:
    """The values of `setup`'s step; its other keys are the step's arguments (a string: one word,
    a list: its words)."""
    arguments = dict(setup)
    name = arguments.pop("step", None)
    if name not in STEPS:
        raise TemplateError(f"setup: unknown step {name!r} (the steps: {', '.join(STEPS)})")
    values = {key: scope.evaluate(v) if isinstance(v, list) else scope.word(v) for key, v in arguments.items()}
    try:
        return STEPS[name](scope, **values)
    except TypeError as e:
        raise TemplateError(f"setup: step {name}: {e}") from None
