#!/usr/bin/env python3
"""Self-test of eval_ensemble's --match-colour (run by CTest; exit code != 0 on failure), on the
bundled tiles and a bundled network's model.yaml.

1. A field's colour statistics are those of its labelled ground only: tile 1 with a block of its
   labels set to ignore and that block painted white keeps the statistics of the rest.
2. A member's training colour is the mean of its training fields' statistics: tile 1's
   leave-one-tile-out network trained on tiles 2 to 6.
3. Tile 1's image matched to them: each pixel is the affine match, rounded, or clipped at 0 or
   255 where that falls outside; an image that needs no clipping takes the training mean and
   standard deviation per channel.
4. A member whose model.yaml names no training field, or one not in examples/data, is refused.

Needs torch, as eval_ensemble does: CTest's tools:eval_colour is skipped (exit 77) without it.
"""

from __future__ import annotations

import copy

from tool_output import check, check_refused, require_torch

require_torch()

import numpy as np  # noqa: E402
import yaml  # noqa: E402

from adaptseg_tools import REPO  # noqa: E402
from adaptseg_tools.eval_ensemble import colour_stats, match_colour, training_colour  # noqa: E402
from adaptseg_tools.fieldio import IGNORE  # noqa: E402
from adaptseg_tools.training.fields import load_field  # noqa: E402


def main():
    data = REPO / "examples" / "data"
    tile1 = load_field(data / "dubai-tile-1")
    mu, sd = colour_stats(tile1)
    inside = tile1.labels != IGNORE
    pixels = tile1.image[inside].astype(np.float64)
    check(np.allclose(mu, pixels.mean(0)) and np.allclose(sd, pixels.std(0)), f"tile 1's statistics {mu} {sd}")

    painted = copy.copy(tile1)
    painted.labels = tile1.labels.copy()
    painted.image = tile1.image.copy()
    painted.labels[:200, :300] = IGNORE
    painted.image[:200, :300] = 255
    keep = painted.labels != IGNORE
    mu_p, sd_p = colour_stats(painted)
    rest = tile1.image[keep].astype(np.float64)
    check(np.allclose(mu_p, rest.mean(0)) and np.allclose(sd_p, rest.std(0)),
          "the statistics read ground outside the labels")

    meta = yaml.safe_load((REPO / "examples" / "models" / "mobilenetv2-dubai-loto" / "tile-1" / "model.yaml").read_text())
    names = meta["training"]["fields"]
    check(names == [f"dubai-tile-{k}" for k in range(2, 7)], f"tile 1's network trained on {names}")
    cache: dict = {}
    mu_t, sd_t = training_colour(meta, cache)
    each = [colour_stats(load_field(data / n)) for n in names]
    check(np.allclose(mu_t, np.mean([m for m, _ in each], 0)) and np.allclose(sd_t, np.mean([s for _, s in each], 0)),
          "the training colour is not the mean of the fields' own")
    check(sorted(cache) == names, f"cache {sorted(cache)}")

    matched = match_colour(tile1.image, (mu, sd), (mu_t, sd_t))
    check(matched.dtype == np.uint8 and matched.shape == tile1.image.shape, "matched image type or shape")
    check(np.abs(mu - mu_t).max() > 20, "tile 1 is brighter than its training tiles: the check would be empty")
    affine = (tile1.image.astype(np.float64) - mu) / sd * sd_t + mu_t
    got = matched.astype(np.float64)
    within = (affine > 0) & (affine < 255)
    check(np.abs(got - affine)[within].max() <= 0.5, "a pixel inside 0..255 is not the affine match, rounded")
    check((got[affine <= 0] == 0).all() and (got[affine >= 255] == 255).all(), "a pixel outside 0..255 is not clipped")
    check(within.mean() > 0.5, "most of the tile clipped: the check would say little")
    # Gaussian noise, matched to a mean and spread well inside 0..255: those, within rounding (no clipping).
    rng = np.random.default_rng(0)
    noise = np.clip(rng.normal(128, 20, (300, 400, 3)), 0, 255).round().astype(np.uint8)
    n_mu, n_sd = noise.reshape(-1, 3).mean(0), noise.reshape(-1, 3).std(0)
    out = match_colour(noise, (n_mu, n_sd), (np.array([100.0, 110.0, 120.0]), np.array([30.0, 25.0, 20.0])))
    o = out.reshape(-1, 3).astype(np.float64)
    check(np.abs(o.mean(0) - [100, 110, 120]).max() < 0.6 and np.abs(o.std(0) - [30, 25, 20]).max() < 0.6,
          f"matched noise mean {o.mean(0)} std {o.std(0)}")

    def colour_of(meta):
        return training_colour(meta, {})

    check_refused(colour_of, {"training": {}}, "names no training fields", "a model.yaml without training fields")
    check_refused(colour_of, {"training": {"fields": ["dubai-tile-9"]}}, "dubai-tile-9 is not in",
                  "a training field not in examples/data")
    print("ok: colour statistics over the labelled ground, the training fields' mean, the match, refusals")


if __name__ == "__main__":
    main()
