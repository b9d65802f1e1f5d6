"""Summary of adaptseg_cell_study outputs (docs/results.md, "Cells").

Usage: cat STUDY.md ... | PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.cell_study_table

Reads the Markdown that adaptseg_cell_study prints (one or more runs, each with --decision-model), and
prints, as Markdown:
  1. per (field, class, GSD) group: the planner's input and its capture of the achievable positive
     gain at 20 % of the cells, against the best possible and a random choice;
  2. per decision input: the mean rank correlation and capture at 10 % and 20 % over the groups,
     with the planner's ranking (each group ranked by its own model's input) and the best and
     random captures.
"""
import re
import statistics
import sys


def cells(line):
    return [c.strip() for c in line.strip().strip("|").split("|")]


def main():
    inputs, groups = [], []
    for line in sys.stdin:
        if line.startswith("| field |"):
            inputs = [c.split(":")[0] for c in cells(line)[7:]]
        elif line.startswith("| mean |") or line.startswith("|---") or not line.startswith("| "):
            m = re.match(r"the planner's ranking \((\w+), from .*\): mean capture of the achievable positive gain "
                         r"([-\d.na]+) at 10 % and ([-\d.na]+) at 20 %", line)
            if m and groups:
                groups[-1]["planner"] = (m.group(1), float(m.group(2)), float(m.group(3)))
        else:
            c = cells(line)
            g = {"field": c[0], "class": c[1], "gsd": c[2], "best": float(c[5]), "random": float(c[6]), "inputs": {}}
            for name, v in zip(inputs, c[7:]):
                rho, c10, c20 = (float(x) for x in v.split("/"))
                g["inputs"][name] = (rho, c10, c20)
            groups.append(g)
    if not groups:
        sys.exit("no adaptseg_cell_study table on standard input")
    print("| field | class | GSD [cm/px] | planner's input | its capture at 20 % | best at 20 % | random at 20 % |")
    print("| --- | --- | ---: | --- | ---: | ---: | ---: |")
    for g in groups:
        p = g.get("planner")
        print(f"| {g['field']} | {g['class']} | {g['gsd']} | {p[0] if p else '—'} | "
              f"{p[2]:.2f} | {g['best']:.2f} | {g['random']:.2f} |" if p else
              f"| {g['field']} | {g['class']} | {g['gsd']} | — | — | {g['best']:.2f} | {g['random']:.2f} |")
    print()
    print("| ranking | Spearman | capture at 10 % | capture at 20 % |")
    print("| --- | ---: | ---: | ---: |")

    def mean(values):
        values = [v for v in values if v == v]
        return statistics.mean(values) if values else float("nan")

    for name in inputs:
        rows = [g["inputs"][name] for g in groups if name in g["inputs"]]
        if all(r[2] != r[2] for r in rows):
            continue  # unknown from this backend (adaptseg_cell_study prints nan): no row
        print(f"| {name} | {mean(r[0] for r in rows):+.2f} | {mean(r[1] for r in rows):.2f} | "
              f"{mean(r[2] for r in rows):.2f} |")
    with_planner = [g for g in groups if "planner" in g]
    if with_planner:
        print(f"| **the planner's (each run's model)** | {mean(g['inputs'][g['planner'][0]][0] for g in with_planner):+.2f} | "
              f"{mean(g['planner'][1] for g in with_planner):.2f} | {mean(g['planner'][2] for g in with_planner):.2f} |")
    print(f"| best possible (hindsight) | | | {mean(g['best'] for g in groups):.2f} |")
    print(f"| random | | | {mean(g['random'] for g in groups):.2f} |")


if __name__ == "__main__":
    main()
