"""``evobiped presets``: the named run settings ``evolve --preset`` takes."""

from __future__ import annotations



def add_presets(sub) -> None:
    p = sub.add_parser("presets", help="list the named run settings for `evolve --preset NAME`")
    p.set_defaults(func=run_presets_cmd)


def run_presets_cmd(args) -> int:
    from ..files.presets import describe, names

    width = max(map(len, names()))
    for name in names():
        print(f"{name:<{width}}  {describe(name)}")
    return 0


SUBCOMMANDS = (add_presets,)
