"""Each training field's own slope against its mean top-level entropy, and the slope the
field-entropy pooling forecasts for each field left out (docs/method.md, "Cells that pay").

Reads the cell samples that `adaptseg_calibrate --cell-samples-csv` writes and prints, per pair
of GSDs, each field's own slope b_f of the normalised gain on INPUT (least squares through the
origin, cells weighted by their field pixels) with its mean top-level entropy u_f, then, for each
field, the slope forecast from the other fields' line b = a + c*u (weighted least squares, equal
weights: the random-effects fit where the fields disagree beyond their cells' scatter, as they
do on new ground), clamped to their range of u; and how many forecasts have the field's own sign.

  entropy_slopes.py CELLS.csv INPUT [--covariates]

--covariates: instead, per pair of GSDs, how well each field-level quantity the UAV has before it
descends (the field's pixel-weighted mean of every top-level input, top_<name>, and its sigma)
orders the fields' own slopes: the Spearman rank correlation over the fields, and how many fields
the line in it fitted on the others forecasts with their own sign (as the entropy line above). Six
fields tell a covariate from chance poorly: one that orders the slopes at every pair of GSDs, with
one sign, is what a design could use.

  entropy_slopes.py CELLS.csv INPUT --within

--within: for cells of sub-fields named FIELD[region] (adaptseg_calibrate --train FIELD:x0,y0,x1,y1,
e.g. each tile's quadrants), how far the sub-fields' own slopes spread between the fields and
within them, per pair of GSDs: each sub-field's slope (as above); within a field, the sub-fields'
spread about their field's mean less what the cells' sampling scatter alone makes of it (the same
spread with each field's cells dealt at random to its sub-fields, 200 times, seeded), with p, the
share of those deals that spread as far as the real sub-fields (1 + count over 1 + deals); between
the fields, the spread of the fields' means less what the spread within makes of a mean of n
sub-fields (n the harmonic mean); and the local share, within / (within + between) (- where both
are 0). A slope that is the field's would leave nothing within, and p would be far from 0.
"""
import math
import random
import sys

from .proxy_slopes import cell_pairs, normalized_gain
from .proxy_table import spearman


def own_slope(cells, inp, mean_px):
    wxx = wxg = pu = px = 0.0
    for c in cells:
        x = float(c["top_" + inp])
        w = float(c["field_px"]) / mean_px
        nu = normalized_gain(c)
        wxx += w * x * x
        wxg += w * x * nu
        u = float(c["top_entropy"])
        if math.isfinite(u):
            pu += float(c["field_px"]) * u
            px += float(c["field_px"])
    return (wxg / wxx if wxx > 0 else math.nan, pu / px if px > 0 else math.nan)


def line_forecast(points, u):
    """b at u of the least-squares line through `points` (u_f, b_f), u clamped to their range."""
    n = len(points)
    mu = sum(p[0] for p in points) / n
    mb = sum(p[1] for p in points) / n
    suu = sum((p[0] - mu) ** 2 for p in points)
    c = sum((p[0] - mu) * (p[1] - mb) for p in points) / suu if suu > 0 else 0.0
    lo, hi = min(p[0] for p in points), max(p[0] for p in points)
    return mb + c * (min(max(u, lo), hi) - mu)


def left_out_forecasts(points):
    """{field: the slope the line through the other fields' (u, b) forecasts at its u} for every
    field of `points` ({field: (u, b)}), where the others are two at least."""
    if len(points) < 3:
        return {}
    return {n: line_forecast([points[m] for m in points if m != n], points[n][0]) for n in points}


def field_covariates(cells):
    """{name: pixel-weighted mean over `cells`} of every top-level input, and the field's sigma."""
    px = sum(float(c["field_px"]) for c in cells)
    out = {}
    for col in cells[0]:
        if not col.startswith("top_") or col == "top_gsd_cm":
            continue
        vals = [(float(c["field_px"]), float(c[col])) for c in cells]
        if all(math.isfinite(v) for _, v in vals):
            out[col[4:]] = sum(w * v for w, v in vals) / px
    out["field_sigma"] = float(cells[0]["field_sigma"])
    return out


def covariates(pairs, fields, inp):
    """Prints, per pair of GSDs, each covariate's rank correlation with the fields' own slopes and
    its leave-one-field-out sign count."""
    names = None
    rows = []
    for key in sorted(pairs):
        cells = pairs[key]
        mean_px = sum(float(c["field_px"]) for c in cells) / len(cells)
        per = {n: [c for c in cells if c["field"] == n] for n in fields}
        per = {n: cs for n, cs in per.items() if cs}
        slope = {n: own_slope(cs, inp, mean_px)[0] for n, cs in per.items()}
        known = [n for n in per if math.isfinite(slope[n])]
        if len(known) < 3:
            continue
        cov = {n: field_covariates(per[n]) for n in known}
        if names is None:
            names = [c for c in cov[known[0]] if all(c in cov[n] for n in known)]
        cols = []
        b = [slope[n] for n in known]
        for name in names:
            if any(name not in cov[n] for n in known):
                cols.append("-")  # not finite on every field at this pair of GSDs
                continue
            u = [cov[n][name] for n in known]
            forecasts = left_out_forecasts({n: (cov[n][name], slope[n]) for n in known})
            right = sum((f > 0) == (slope[n] > 0) for n, f in forecasts.items())
            rho = spearman(u, b)
            cols.append(f"{rho:+.2f} ({right}/{len(known)})" if math.isfinite(rho) else f"no spread ({right}/{len(known)})")
        rows.append(f"| {key[0]:g} -> {key[1]:g} | " + " | ".join(cols) + " |")
    if names is None:
        sys.exit("no pair of GSDs with three fields whose slope is known")
    print(f"input {inp}: per covariate, rank correlation with the fields' own slopes (signs right, leave one field out)")
    print("| top -> descent [cm/px] | " + " | ".join(names) + " |")
    print("| --- | " + " | ".join("---:" for _ in names) + " |")
    print("\n".join(rows))


def pooled_within(slopes):
    """The pooled variance of sub-field slopes about their field's mean ({field: {sub-field:
    slope}}, fields of two or more)."""
    ss = dof = 0.0
    for bs in slopes.values():
        m = sum(bs.values()) / len(bs)
        ss += sum((b - m) ** 2 for b in bs.values())
        dof += len(bs) - 1
    return ss / dof if dof > 0 else math.nan


def sub_field_slopes(cells_by_sub, group, inp, mean_px):
    """{field: {sub-field: its slope}} of the sub-fields whose slope is finite, fields of two or
    more such."""
    by = {}
    for n, cs in cells_by_sub.items():
        b = own_slope(cs, inp, mean_px)[0]
        if math.isfinite(b):
            by.setdefault(group[n], {})[n] = b
    return {g: bs for g, bs in by.items() if len(bs) >= 2}


def within(pairs, fields, inp, shuffles=200):
    """Prints, per pair of GSDs, the sub-fields' own slopes' spread between and within their fields
    beyond the cells' sampling scatter (--within). The sampling part is measured, not modelled:
    each field's cells dealt at random to its sub-fields (those with a slope), as many to each as
    it has, `shuffles` times (seeded), so that a sub-field no longer stands for a place and the
    spread of the slopes within the fields is what the cells alone make."""
    group = {n: n.split("[", 1)[0] for n in fields}
    sizes = [sum(1 for n in fields if group[n] == g) for g in set(group.values())]
    if len(sizes) < 2 or min(sizes) < 2:
        sys.exit("--within: needs two fields or more, each of two sub-fields or more, named FIELD[region]")
    print(f"input {inp}: the sub-fields' own slopes, their spread between the fields and within them "
          f"beyond the cells' sampling scatter (standard deviations; sampling: cells dealt at random to "
          f"the sub-fields of their field, {shuffles} times)")
    print("| top -> descent [cm/px] | sub-fields | mean slope | between fields | within fields | "
          "sampling | p (within from sampling alone) | local share |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for key in sorted(pairs):
        cells = pairs[key]
        mean_px = sum(float(c["field_px"]) for c in cells) / len(cells)
        subs = {}
        for c in cells:
            subs.setdefault(c["field"], []).append(c)
        by = sub_field_slopes(subs, group, inp, mean_px)
        if len(by) < 2:
            continue
        within_var = pooled_within(by)
        rng = random.Random(f"{key[0]}:{key[1]}")
        shuffled, at_least = [], 0
        for _ in range(shuffles):
            dealt = {}
            for bs in by.values():
                pool = [c for n in bs for c in subs[n]]
                rng.shuffle(pool)
                i = 0
                for n in bs:
                    dealt[n] = pool[i:i + len(subs[n])]
                    i += len(subs[n])
            v = pooled_within(sub_field_slopes(dealt, group, inp, mean_px))
            if math.isfinite(v):
                shuffled.append(v)
                at_least += v >= within_var
        sampling = sum(shuffled) / len(shuffled) if shuffled else math.nan
        n_sub = sum(len(bs) for bs in by.values())
        means = {g: sum(bs.values()) / len(bs) for g, bs in by.items()}
        grand = sum(means.values()) / len(means)
        between_var = sum((m - grand) ** 2 for m in means.values()) / (len(means) - 1)
        n_h = len(by) / sum(1.0 / len(bs) for bs in by.values())
        w_true = max(0.0, within_var - sampling)
        b_true = max(0.0, between_var - within_var / n_h)
        share = f"{w_true / (w_true + b_true):.2f}" if w_true + b_true > 0 else "-"
        mean_b = sum(b for bs in by.values() for b in bs.values()) / n_sub
        p = (1 + at_least) / (1 + len(shuffled))
        print(f"| {key[0]:g} -> {key[1]:g} | {n_sub} | {mean_b:+.3f} | {math.sqrt(b_true):.3f} | "
              f"{math.sqrt(w_true):.3f} | {math.sqrt(sampling):.3f} | {p:.3f} | {share} |")


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    flags = [a for a in argv if a.startswith("--")]
    args = [a for a in argv if not a.startswith("--")]
    if len(args) != 2 or len(flags) > 1 or any(f not in ("--covariates", "--within") for f in flags):
        sys.exit(__doc__)
    path, inp = args
    pairs, fields = cell_pairs(path, inp)
    if flags == ["--covariates"]:
        covariates(pairs, fields, inp)
        return 0
    if flags == ["--within"]:
        within(pairs, fields, inp)
        return 0
    if any("top_entropy" not in cells[0] for cells in pairs.values()):
        sys.exit(f"{path}: no column top_entropy")
    print(f"{path}: input {inp}; per field: own slope b_f @ mean entropy u_f -> forecast from the others")
    print("| top -> descent [cm/px] | signs right | " + " | ".join(fields) + " |")
    print("| --- | ---: | " + " | ".join("---" for _ in fields) + " |")
    for key in sorted(pairs):
        cells = pairs[key]
        mean_px = sum(float(c["field_px"]) for c in cells) / len(cells)
        own = {n: own_slope([c for c in cells if c["field"] == n], inp, mean_px) for n in fields}
        known = [n for n in fields if all(math.isfinite(v) for v in own[n])]
        forecasts = left_out_forecasts({n: own[n][::-1] for n in known})
        cols, right, counted = [], 0, 0
        for n in fields:
            if n not in known:
                cols.append("-")
                continue
            if n not in forecasts:
                cols.append(f"{own[n][0]:+.3f} @ {own[n][1]:.2f}")
                continue
            f = forecasts[n]
            counted += 1
            right += (f > 0) == (own[n][0] > 0)
            cols.append(f"{own[n][0]:+.3f} @ {own[n][1]:.2f} -> {f:+.3f}")
        print(f"| {key[0]:g} -> {key[1]:g} | {right} of {counted} | " + " | ".join(cols) + " |")
    return 0


if __name__ == "__main__":
    main()
