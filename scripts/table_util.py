"""Helpers of the markdown table scripts (gbuffer_table.py, msaa_table.py) over `visbuf bench` JSON rows."""


def ms(v):
    """Milliseconds as the tables print them: 3 significant-ish digits."""
    return f"{v:,.1f}" if v >= 10 else f"{v:.2f}"


def group(passes, keys):
    """Sum of the median times of the passes named by keys (a key also matches "key early" / "key late")."""
    return sum(v["median"] for k, v in passes.items() if any(k == g or k.startswith(g + " ") for g in keys))
