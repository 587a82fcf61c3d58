"""Newton on one barrier vertex: where a primal-dual barrier model helps and where it hurts.

Isolation for issue 31 (notes/performance.md, 2026-12-01): the four chains' long contact steps
are walk-outs, and a primal-dual model of the barrier (each vertex keeps the barrier slope
Newton's linear model predicted after the step, and the next direction uses the barrier's
second-order model about the gap that slope implies) was tried in the simulator and changed
nothing (1000 -> 993 / 1004 Newton iterations). This 1D model shows why:

    f(y) = kappa P_s(y) + K/2 (y - yhat)^2,   P_s(y) = (y - s)^4 / y^5 on (0, s)

(one vertex of a contact pair: the barrier against the rest of the step objective, an inertia-
like spring K). The equilibrium y* and K are set from the ratio K / (kappa P_s''(y*)); Newton
starts at y0 < y* (inside the barrier, as after an impact) and stops at |f'| <= 1e-8 |kappa
P_s'(y*)|. Full steps, halved until f decreases (the simulator's Armijo search, simplified).

Prints, per case, the iterations of plain Newton, of Newton with the barrier model, and of the
model with the geometric mean of the two curvatures (tried second; also no gain in the simulator). The
model wins by a factor 2-4 when the barrier dominates the curvature (K / kappa P'' = 0.01), is
even at 1, and loses when the spring dominates (100): its dual is the spring's force at the
current point, and the gap that force implies is far from the equilibrium when the spring's
force changes along the way. In the simulator the four chains' contact steps went both ways
(one step 7 -> 4 iterations, another 3 -> 6), consistent with a mix of the two kinds: their
gaps at the solution sit at 0.6-0.9 s, near the support's edge where P_s'' is small.

    .venv/bin/python tools/bench/barrier_newton_1d.py
"""

import math

S = 5e-3  # the four chains' barrier width (robots/four_chains.yaml, contact.s)
R_MIN = 1e-2  # smallest dual/primal slope ratio the model uses (as in the simulator trial)


def p(y):
    t = y - S
    return t**4 / y**5 if 0 < y < S else (0.0 if y >= S else math.inf)


def d1(y):
    t = y - S
    return t**3 * (5 * S - y) / y**6 if y < S else 0.0


def d2(y):
    t = y - S
    return 2 * t * t * (y * y - 10 * S * y + 15 * S * S) / y**7 if y < S else 0.0


def inverse_slope(lam, lo):
    """(P_s')^-1(lam) on [lo, s): P_s' increases on (0, s)."""
    a, b = lo, S
    for _ in range(200):
        m = 0.5 * (a + b)
        if d1(m) < lam:
            a = m
        else:
            b = m
    return 0.5 * (a + b)


def model(y, lam, geometric=False):
    """Slope and curvature the direction uses at y for the dual lam (primal without a softer
    dual): the barrier's second-order model about the dual's gap xb; with `geometric`, its
    curvature is sqrt(P''(xb) P''(y)) (the session's second registration, R2)."""
    p1, p2 = d1(y), d2(y)
    r = lam / p1 if p1 < 0 else 2.0
    if not r < 1:
        return p1, p2
    xb = inverse_slope(max(r, R_MIN) * p1, y)
    c = math.sqrt(d2(xb) * p2) if geometric else d2(xb)
    return d1(xb) + c * (y - xb), c


def newton(kappa, k, yhat, y0, variant, tol):
    def f(y):
        return kappa * p(y) + 0.5 * k * (y - yhat) ** 2

    def g(y):
        return kappa * d1(y) + k * (y - yhat)

    y, lam, it = y0, -math.inf, 0
    while abs(g(y)) > tol and it < 200:
        if variant == "plain":
            m1, m2 = d1(y), d2(y)
        else:
            m1, m2 = model(y, lam, geometric=variant == "geometric")
        dy = -(kappa * m1 + k * (y - yhat)) / (kappa * m2 + k)
        a = 1.0
        while (y + a * dy <= 0 or f(y + a * dy) > f(y)) and a > 1e-12:
            a *= 0.5
        lam = m1 + m2 * a * dy
        y += a * dy
        it += 1
    return it


def main():
    print("| y*/s | y0/s | K / (kappa P''(y*)) | plain Newton | barrier model | geometric-mean curvature |")
    print("|---:|---:|---:|---:|---:|---:|")
    totals = {"plain": 0, "model": 0, "geometric": 0}
    kappa = 1.0
    for ystar_s in (0.2, 0.4, 0.6, 0.75, 0.85, 0.95):
        ys = ystar_s * S
        for ratio in (0.01, 1.0, 100.0):
            k = ratio * kappa * d2(ys)
            yhat = ys + kappa * d1(ys) / k  # f'(y*) = 0
            tol = 1e-8 * abs(kappa * d1(ys))
            for start in (0.5, 0.8):
                y0 = start * ys
                its = {v: newton(kappa, k, yhat, y0, v, tol) for v in totals}
                for v, n in its.items():
                    totals[v] += n
                print(
                    f"| {ystar_s:.2f} | {start * ystar_s:.2f} | {ratio:g} | {its['plain']} "
                    f"| {its['model']} | {its['geometric']} |"
                )
    print(f"\ntotal iterations: {totals}")


if __name__ == "__main__":
    main()
