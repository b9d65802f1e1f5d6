#!/usr/bin/env python3
"""Self-test of eval_ensemble's test-time coarser look (@coarseG, OnnxParams::test_time_coarse_gsd_cm;
run by CTest; exit code != 0 on failure), on a bundled tile and a bundled network.

1. The coarser pass's GSD: min(G, 2 x the image's GSD) where at least 10 % coarser, else none
   (the values tests/test_ensemble_segmenter.cpp checks on OnnxSegmenter::coarse_gsd_cm).
2. Member settings: @coarse10, @mirror@coarse10 and plain parse; an unknown or empty setting is
   refused naming the known ones.
3. Every eighth image of tile 5 at 5 cm/px by the network that never saw it: the probabilities
   with coarse 10 are the mean of the plain pass and of one at half the input size (256 x 192),
   their labels differ from the plain ones somewhere, and an image at 10 cm/px gets the plain
   pass alone.

Needs torch, as eval_ensemble does: CTest's tools:eval_coarse is skipped (exit 77) without it.
"""

from __future__ import annotations

from tool_output import check, require_torch

require_torch()

import numpy as np  # noqa: E402

from adaptseg_tools import REPO  # noqa: E402
from adaptseg_tools.eval_ensemble import coarse_gsd, load_member, member_dir, member_probabilities, one_pass  # noqa: E402
from adaptseg_tools.training.fields import capture, lawnmower_rects, load_field  # noqa: E402


def main():
    # 1. Which images get a second pass, and at what GSD.
    for g, gsd, want in ((10, 5, 10), (10, 7.5, 10), (10, 9.5, 0), (10, 2, 4), (15, 10, 15), (0, 5, 0), (10, 10, 0)):
        check(coarse_gsd(g, gsd) == want, f"coarse_gsd({g}, {gsd}) = {coarse_gsd(g, gsd)}, expected {want}")

    # 2. Member settings.
    net = REPO / "examples" / "models" / "mobilenetv2-dubai-loto" / "tile-5"
    check(member_dir(f"{net}@coarse10") == (net.resolve(), False, 10.0), "@coarse10")
    check(member_dir(f"{net}@mirror@coarse12.5") == (net.resolve(), True, 12.5), "@mirror@coarse12.5")
    check(member_dir(str(net)) == (net.resolve(), False, 0.0), "no setting")
    for bad in ("@coarse", "@coarse0", "@flip"):
        try:
            member_dir(f"{net}{bad}")
        except SystemExit as e:
            check("known: @mirror, @coarseG" in str(e), f"{bad} refused with {e}")
        else:
            check(False, f"{bad} was not refused")

    # 3. Images of tile 5 at its own GSD, and one at twice it.
    model, spec, meta = load_member(net)
    field = load_field(REPO / "examples" / "data" / "dubai-tile-5")
    rects = list(lawnmower_rects(field, field.gsd_cm, spec.camera_wh))
    changed = []
    for rect in rects[::8]:
        bgr, _, _ = capture(field, *rect, spec.camera_wh)
        plain = member_probabilities(model, spec, meta, bgr)
        both = member_probabilities(model, spec, meta, bgr, coarse_gsd_cm=10, gsd_cm=field.gsd_cm)
        half = one_pass(model, spec, meta, bgr, (256, 192), False)
        check(np.allclose(both, 0.5 * (plain + half), atol=1e-6), "coarse 10 at 5 cm/px: the mean of the two passes")
        check(np.allclose(both.sum(0), 1.0, atol=1e-5), "probabilities sum to 1")
        changed.append((both.argmax(0) != plain.argmax(0)).mean())
    check(0.005 < np.mean(changed) < 0.5, f"labels changed by the coarser pass: {np.mean(changed):.4f} of the images")
    at10 = member_probabilities(model, spec, meta, bgr, coarse_gsd_cm=10, gsd_cm=2 * field.gsd_cm)
    check(np.array_equal(at10, plain), "an image at 10 cm/px gets the plain pass alone")
    print("eval_ensemble's coarser look: ok")


if __name__ == "__main__":
    main()
