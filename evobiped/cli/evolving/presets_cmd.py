"""``evobiped presets``: the named run settings ``evolve --preset`` takes."""

from __future__ import annotations



def add_presets(sub) -> None:
    p = sub.add_parser("presets", help="list the named run settings for `evolve --preset NAME`")
    p.set_defaults(func=run_presets_cmd)


def run_presets_cmd(args) -> int:
    from ...core.fileio import read_toml
    from ...files.presets import describe, names, path, split_declarations

    width = max(map(len, names()))
    for name in names():
        needs = split_declarations(name, read_toml(path(name)))[1]["needs_start"]
        print(f"{name:<{width}}  {describe(name)}{' (needs --from)' if needs else ''}")
    return 0


SUBCOMMANDS = (add_presets,)
