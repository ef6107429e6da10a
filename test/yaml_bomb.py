"""A YAML alias bomb ("billion laughs") for tests: levels of anchors, each a list of ten aliases of the one below."""


def alias_bomb(levels: int = 7, indent: str = "  ") -> str:
    """The lines of a mapping, each indented by ``indent``, whose last key's value expands to 10**levels strings
    (7 levels: 1e7, past config_yaml.MAX_ALIASED_NODES yet small enough to show on code that would expand it)."""
    lines = ['a0: &a0 "lol"']
    lines += [f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 10) + "]" for i in range(1, levels + 1)]
    return "".join(f"{indent}{line}\n" for line in lines)
