"""``evobiped select``: the walker of a run chosen by simulating its best candidates for longer (selected.json)."""

from __future__ import annotations

from ...flags import add_allow_unfinished, note, positive_float, positive_int


def add_select(sub) -> None:
    p = sub.add_parser("select", help="re-simulate a run's fittest generation bests (and its --from genome) for "
                                      "longer; writes the best as selected.json")
    p.add_argument("run", metavar="RUN", help="a run directory")
    p.add_argument("--top", type=positive_int, default=8, metavar="K",
                   help="the generation bests of the K fittest generations (default 8)")
    p.add_argument("--seconds", type=positive_float, default=200.0, metavar="S",
                   help="each candidate up through its episode runs S s alone (default 200)")
    p.add_argument("--heading-limit", type=positive_float, default=30.0, metavar="DEG",
                   help="prefer walkers within DEG of their initial facing (default 30)")
    p.add_argument("--walking", action="store_true", help="prefer a walk: each candidate's gait over its first 50 s "
                   "against the walking criteria (evobiped gait-report), first in the ranking")
    add_allow_unfinished(p)
    p.set_defaults(func=run_select_cmd)


def run_select_cmd(args) -> int:
    from ...usecases.selecting import select_walker

    s = select_walker(args.run, top=args.top, seconds=args.seconds, heading_limit=args.heading_limit,
                      walking=args.walking, note=note, allow_unfinished=args.allow_unfinished)
    print(f"{'candidate':<40}{'episode':>14}{'distance (m)':>14}{'heading':>9}{f'up {args.seconds:g} s':>10}"
          + ("  walks" if args.walking else ""))
    for i, (label, r) in enumerate(zip(s.labels, s.rows)):
        ep = "fell %.1f s" % r["end_time"] if r["fell"] else "up"
        h = "-" if r["heading_deg"] is None else f"{r['heading_deg']:+.0f} deg"
        mark = "  <- selected" if i == s.chosen else ""
        walks = "" if not args.walking else "  yes" if r["walks"] else "  no: " + ", ".join(r["failed"])
        print(f"{label:<40}{ep:>14}{r['distance']:>14.2f}{h:>9}{'yes' if r.get('up_long') else 'no':>10}{walks}{mark}")
    print(f"selected: {s.labels[s.chosen]} -> {s.path}")
    return 0


SUBCOMMANDS = (add_select,)
