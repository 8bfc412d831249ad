"""``evobiped adapt``: a gait repertoire adapting to a damaged body by intelligent trial and error (Cully et al.
2015)."""

from __future__ import annotations

from ...flags import nonnegative_float, positive_float, positive_int, seed, within
from ...repertoire.trial_error import ORDERS, TrialAndError


def add_adapt(sub) -> None:
    p = sub.add_parser("adapt", help="find a gait of a map-elites run's archive that walks on a damaged body "
                                     "(intelligent trial and error)")
    p.add_argument("run", metavar="RUN", help="a map-elites run directory (its archive.json)")
    p.add_argument("--damage", required=True, action="append", metavar="KIND:PART[:AMOUNT]",
                   help="weak:JOINT:F (strength kept, 0-1), locked:JOINT or short:LEG:D (m); repeat for several cases")
    p.add_argument("--seconds", type=positive_float, default=50.0, metavar="S",
                   help="length of each trial (default 50 s)")
    p.add_argument("--trials", type=positive_int, default=20, metavar="N", help="most trials per damage (default 20)")
    p.add_argument("--rho", type=within(1e-3, 1e3, "scaled measure units", "the measures span 0 to 1"),
                   default=TrialAndError.rho, metavar="R",
                   help=f"the GP kernel's length scale in scaled measure units (default {TrialAndError.rho}; Cully et "
                        "al. 0.4)")
    p.add_argument("--kappa", type=nonnegative_float, default=TrialAndError.kappa, metavar="K",
                   help=f"exploration weight of the upper confidence bound mu + K s (default {TrialAndError.kappa})")
    p.add_argument("--order", choices=ORDERS, default="ucb",
                   help="how the next trial is chosen: the GP's upper confidence bound (default), the best prior "
                        "first, or at random")
    p.add_argument("--pose-noise", type=within(0, 0.5, "rad", "29 deg off each joint's nominal angle"), default=0.0,
                   metavar="RAD",
                   help="each trial's initial joint angles off by Gaussian noise of this sd "
                        "(default 0: nominal trials)")
    p.add_argument("--seed", type=seed, default=0, help="the noisy trials' and the random order's seed (default 0)")
    p.set_defaults(func=run_adapt_cmd)


def run_adapt_cmd(args) -> int:
    import time

    from ...repertoire.adaptation import adapt, walks
    from ...repertoire.damage import parse_damage
    from ...repertoire.elites import load_repertoire

    rep = load_repertoire(args.run)
    damages = [parse_damage(d, rep.episode) for d in args.damage]  # every one checked before any trial
    a = rep.archive
    search = TrialAndError(trials=args.trials, rho=args.rho, kappa=args.kappa, order=args.order, seed=args.seed)
    for damage in damages:
        t0 = time.perf_counter()
        trials, prior = adapt(rep, damage, seconds=args.seconds, search=search, pose_noise=args.pose_noise,
                              seed=args.seed)
        first_tried = "a random elite" if args.order == "random" else "the archive's best walker"
        print(f"damage {damage}: {len(prior)} walking elites; {first_tried} (predicted {trials[0].predicted:.1f} m) "
              f"on the damaged body: {trials[0].distance:.1f} m, "
                  + (f"fell at {trials[0].end_time:.1f} s" if trials[0].fell else "up"))
        for n, t in enumerate(trials, 1):
            print(f"  trial {n}: cell {a.cell[t.elite, 0]},{a.cell[t.elite, 1]} "
                  f"({', '.join(f'{m} {v:.3g}' for m, v in zip(a.measures, a.values[t.elite]))}): predicted "
                  f"{t.predicted:.1f} m, walked {t.distance:.1f} m, "
                      + (f"fell at {t.end_time:.1f} s" if t.fell else f"up {t.end_time:g} s"))
        first = next((n for n, t in enumerate(trials, 1) if walks(t)), None)
        verdict = f"walks (>= 10 m, no fall) from trial {first}" if first else "no trial walked (>= 10 m, no fall)"
        print(f"  {verdict}; "
              f"{len(trials)} trials, {time.perf_counter() - t0:.1f} s")
    return 0


SUBCOMMANDS = (add_adapt,)
