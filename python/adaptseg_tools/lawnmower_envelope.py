"""The lawnmower curve's upper envelope, as the library computes it and reads the front margin
against it (include/adaptseg/core/lawnmower_curve.hpp: upper_envelope, front_margin), for the Python
tools that read results.csv (plot_evaluation.py, backend_compare.py)."""


def upper_envelope(points):
    """The lawnmower curve's running maximum over time as points ((time, mIoU), sorted by time),
    as adaptseg::upper_envelope computes it: flat after a lawnmower that a slower one does not
    beat, back on the curve where it climbs through that level."""
    points = sorted(points)
    env = [points[0]]
    best = points[0][1]
    for (ta, ma), (tb, mb) in zip(points, points[1:]):
        if not mb > best:
            continue
        if ma < best and tb > ta:
            env.append((ta + (best - ma) / (mb - ma) * (tb - ta), best))
        env.append((tb, mb))
        best = mb
    return env


def envelope_at(env, t):
    """An envelope's mIoU at time t: linear between its points, flat beyond its ends."""
    if t <= env[0][0]:
        return env[0][1]
    for (t0, m0), (t1, m1) in zip(env, env[1:]):
        if t <= t1:
            return m0 if t1 == t0 else m0 + (m1 - m0) * (t - t0) / (t1 - t0)
    return env[-1][1]

