"""Figures of an adaptseg_evaluate run (paper Figs. results, iouvsh, waypoints, qualitative).

Usage: PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.plot_evaluation OUTDIR

Reads OUTDIR/results.csv, per_image.csv, decisions.csv and strategies.csv (written by
adaptseg_evaluate) and writes
  OUTDIR/miou_vs_time.png       field mIoU over the labels of interest vs execution time
  OUTDIR/per_image_miou.png     per-image mIoU vs image GSD, mean and standard deviation
  OUTDIR/decisions.png          per descent: forecast vs realised field gain (simulation)
  OUTDIR/paths.png              top views of the paths (the coarsest lawnmower, then every strategy of the
                                table of strategies, OUTDIR/strategies.csv), 2 per row
  OUTDIR/maps.png               fused maps vs ground truth (coarsest lawnmower, adaptive)
Needs matplotlib (Debian: python3-matplotlib).
"""
import csv
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.image as mpimg  # noqa: E402

# Per-image figure: the lawnmower images are also shown restricted to those whose footprint's
# ground truth has at least MIN_TRUTH_SIGMA of L (per_image.csv column truth_sigma).
from .lawnmower_envelope import upper_envelope  # noqa: E402
from .per_image_table import MIN_TRUTH_SIGMA, by_gsd  # noqa: E402

# How each strategy is drawn (its legend label comes from the table of strategies,
# OUTDIR/strategies.csv, written by adaptseg_evaluate from kStrategyTable, include/adaptseg/sim/strategy.hpp).
# Hollow ones are drawn over the filled ones: the non-adaptive, tour and row strategies often fly
# adaptive's mission, and both stay visible where they coincide. A strategy without a style here
# is drawn with DEFAULT_STYLE.
STYLE = {
    "adaptive": dict(color="tab:red", marker="*", s=220),
    "nonadaptive": dict(color="tab:blue", marker="s", s=260, hollow=True),
    "tour": dict(color="tab:purple", marker="D", s=150, hollow=True),
    "row": dict(color="tab:orange", marker="o", s=90, hollow=True),
    "linear": dict(color="tab:green", marker="^", s=110),
}
DEFAULT_STYLE = dict(color="tab:gray", marker="P", s=130)


def strategy_table(out):
    """The table of strategies of OUTDIR/strategies.csv in its order: [(name, label)]. Outputs of
    older versions have none: then the names of results.csv, labelled by their names."""
    path = os.path.join(out, "strategies.csv")
    if os.path.exists(path):
        return [(r["name"], r["label"]) for r in read_csv(path)]
    names = dict.fromkeys(r["strategy"] for r in read_csv(os.path.join(out, "results.csv")))
    return [(n, n) for n in names]


def style(strategy, labels):
    """STYLE of `strategy` with its label from the table (`labels`: name -> label)."""
    return dict(DEFAULT_STYLE | STYLE.get(strategy, {}), label=labels.get(strategy, strategy))


def slug(name):
    """A field's name as adaptseg_evaluate names its folder (slug() in adaptseg_evaluate.cpp):
    "weedmap-rededge-000[0.5,0,1,1]" -> "weedmap-rededge-000_region_0.5-0-1-1"."""
    name = name.replace("[", "_region_").replace(",", "-").replace("]", "")
    return re.sub(r"[^A-Za-z0-9.\-]", "_", name)


def save(fig, path, dpi=110, tight=True):
    """Lays out (unless the caller placed the axes: tight=False), writes and closes a figure."""
    if tight:
        fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def num(v):
    return float(v) if v not in ("", None) else float("nan")


def main(out):
    rows = read_csv(os.path.join(out, "results.csv"))
    fields = list(dict.fromkeys(r["field"] for r in rows))
    table = strategy_table(out)
    labels = dict(table)

    # Field mIoU vs execution time (paper Fig. results).
    fig, axes = plt.subplots(1, len(fields), figsize=(6.5 * len(fields), 6.2), squeeze=False)
    for ax, field in zip(axes[0], fields):
        fr = [r for r in rows if r["field"] == field]
        lm = sorted((r for r in fr if r["strategy"] == "lawnmower"), key=lambda r: num(r["time_total"]))
        ax.plot([num(r["time_total"]) for r in lm], [num(r["miou_interest"]) for r in lm], "-o", color="0.3",
                label=labels.get("lawnmower", "lawnmower"))
        env = upper_envelope([(num(r["time_total"]), num(r["miou_interest"])) for r in lm])
        if len(env) != len(lm) or any(e != (num(r["time_total"]), num(r["miou_interest"])) for e, r in zip(env, lm)):
            last = max(num(r["time_total"]) for r in lm)
            if env[-1][0] < last:
                env.append((last, env[-1][1]))  # flat beyond its last rise
            ax.plot([e[0] for e in env], [e[1] for e in env], "--", color="0.55", zorder=1,
                    label="its upper envelope (the front margin's yardstick)")
        for r in lm:
            ax.annotate(f"{num(r['gsd_cm']):.1f} cm/px", (num(r["time_total"]), num(r["miou_interest"])),
                        textcoords="offset points", xytext=(6, -12), fontsize=8, color="0.3")
        for r in fr:
            if r["strategy"] != "lawnmower":
                st = style(r["strategy"], labels)
                hollow = st.get("hollow", False)
                ax.scatter([num(r["time_total"])], [num(r["miou_interest"])], zorder=4 if hollow else 3,
                           label=f"{st['label']} (margin {num(r['front_margin']):+.3f})", marker=st["marker"],
                           s=st["s"], facecolors="none" if hollow else st["color"], edgecolors=st["color"],
                           linewidths=2 if hollow else 1)
        ax.set_xlabel("mission execution time [s] (flight + segmentation + planning)")
        ax.set_ylabel("field mIoU over the labels of interest")
        ax.set_title(field, fontsize=10)
        ax.grid(alpha=0.3)
        # Below the axes: the strategies' points cluster where the legend would sit inside.
        ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2)
    fig.suptitle("Field mIoU vs execution time (above the lawnmower curve: front margin > 0)", fontsize=11)
    save(fig, os.path.join(out, "miou_vs_time.png"))

    # Per-image mIoU vs GSD (paper Fig. iouvsh).
    per = read_csv(os.path.join(out, "per_image.csv"))
    fig, axes = plt.subplots(1, len(fields), figsize=(6.5 * len(fields), 4.5), squeeze=False)
    for ax, field in zip(axes[0], fields):
        # The lawnmower images twice: all of them, and those whose footprint really contains L
        # (truth_sigma >= MIN_TRUTH_SIGMA): an image without L scores 0 for any false positive
        # of L, whatever its GSD.
        series = (("nonadaptive", "tab:blue", "o-", -0.09, None, labels.get("nonadaptive", "nonadaptive")),
                  ("adaptive", "tab:red", "o-", -0.03, None, labels.get("adaptive", "adaptive")),
                  ("lawnmower", "0.4", "o-", 0.03, None, "lawnmowers (all images)"),
                  ("lawnmower", "tab:green", "s--", 0.09, MIN_TRUTH_SIGMA,
                   f"lawnmowers (images with L >= {MIN_TRUTH_SIGMA:.0%} of the truth)"))
        for strategy, color, fmt, offset, min_truth, label in series:
            groups = by_gsd(per, field, strategy, min_truth=min_truth)
            if not groups:
                continue
            g = sorted(groups)
            mean = [sum(groups[k]) / len(groups[k]) for k in g]
            std = [(sum((x - m) ** 2 for x in groups[k]) / len(groups[k])) ** 0.5 for k, m in zip(g, mean)]
            ax.errorbar([k + offset for k in g], mean, yerr=std, fmt=fmt, color=color, capsize=4, label=label)
        ax.set_xlabel("image GSD [cm/px] (higher = flown higher)")
        ax.set_ylabel("per-image mIoU over the labels of interest")
        ax.set_title(field, fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("Per-image mIoU vs GSD:\nmean and standard deviation over the images taken")
    save(fig, os.path.join(out, "per_image_miou.png"))

    # Per descent: the forecast field gain the decision was taken on, against what the descent
    # realised (simulation: the field mIoU with and without its re-mapping).
    path = os.path.join(out, "decisions.csv")
    decisions = read_csv(path) if os.path.exists(path) else []
    decisions = [d for d in decisions if d["action"] == "descend" and d["forecast_field_gain"] != ""
                 and d["realised_field_gain"] != ""]
    if decisions:
        fig, axes = plt.subplots(1, len(fields), figsize=(5.5 * len(fields), 5.6), squeeze=False)
        for ax, field in zip(axes[0], fields):
            lim = 0.0
            for strategy in ("nonadaptive", "adaptive"):
                sel = [d for d in decisions if d["field"] == field and d["strategy"] == strategy]
                if not sel:
                    continue
                f = [num(d["forecast_field_gain"]) for d in sel]
                r = [num(d["realised_field_gain"]) for d in sel]
                lim = max(lim, max(f), max(r))
                st = style(strategy, labels)
                ax.scatter(f, r, color=st["color"], marker=st["marker"], s=st["s"] * 0.5,
                           facecolors="none" if strategy == "nonadaptive" else st["color"],
                           label=f"{st['label']} ({len(sel)} descents)")
                # Adaptive's labels above its points, non-adaptive's below: the two often take the
                # same descents, and their labels would print over each other.
                offset = (5, -9) if strategy == "nonadaptive" else (5, 3)
                for x, y, d in zip(f, r, sel):
                    ax.annotate(f"{num(d['gsd_cm']):g}", (x, y), textcoords="offset points", xytext=offset,
                                fontsize=7, color=st["color"])
            lim = lim * 1.1 if lim > 0 else 1.0
            ax.plot([0, lim], [0, lim], "--", color="0.5", label="realised = forecast")
            ax.set_xlim(min(0.0, ax.get_xlim()[0]), lim)
            ax.set_xlabel("forecast field gain (field mIoU over L)")
            ax.set_ylabel("realised field gain")
            ax.set_title(f"{field}\n(label: descent GSD [cm/px])", fontsize=10)
            ax.grid(alpha=0.3)
            # Below the axes: descents forecast far below what they gained sit in the upper left.
            ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2)
        fig.suptitle("Each descent: the gain it was forecast\nto add to the field mIoU, and what it added", fontsize=11)
        save(fig, os.path.join(out, "decisions.png"))

    # Paths and maps: montages of the per-mission pictures.
    for name, picks in (("paths.png", ["path"]), ("maps.png", ["map"])):
        panels = []
        for field in fields:
            lm = sorted((r for r in rows if r["field"] == field and r["strategy"] == "lawnmower"),
                        key=lambda r: num(r["gsd_cm"]))
            coarsest = f"lawnmower-{num(lm[-1]['gsd_cm']):.2f}"
            wanted = ([coarsest] + [n for n, _ in table if n != "lawnmower"]
                      if name == "paths.png" else [coarsest, "adaptive"])
            for w in wanted:
                p = os.path.join(out, slug(field), w, picks[0] + ".png")
                if os.path.exists(p):
                    panels.append(p)
        if not panels:
            continue
        # A grid at the pictures' own resolution (each panel as large as the largest picture),
        # so no label or map is shrunk: paths two per row, maps (three panels each) one per row.
        images = [mpimg.imread(p) for p in panels]
        cols = 2 if name == "paths.png" else 1
        rows_n = (len(panels) + cols - 1) // cols
        cell_w = max(im.shape[1] for im in images)
        cell_h = max(im.shape[0] for im in images)
        dpi = 100
        fig, axes = plt.subplots(rows_n, cols, figsize=(cell_w * cols / dpi, cell_h * rows_n / dpi), dpi=dpi,
                                 squeeze=False)
        fig.subplots_adjust(left=0, right=1, bottom=0, top=1, wspace=0, hspace=0)
        for ax in axes.flat:
            ax.axis("off")
        for ax, im in zip(axes.flat, images):
            ax.imshow(im, interpolation="nearest")
        save(fig, os.path.join(out, name), dpi=dpi, tight=False)
    print(f"plots written to {out}")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
