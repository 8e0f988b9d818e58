"""The pieces every results generator shares: Markdown tables and the generated blocks of a page.

A page in docs/results/ is hand-written prose; each generated part (a table, figure links, the
reproduce command) sits between `<!-- generated:NAME begin -->` and `<!-- generated:NAME end -->`.
update_page() rewrites the body of the named blocks in place and leaves everything else alone.
"""
import re


def table_row(cells):
    """One Markdown table line; an empty cell is written as `| |`."""
    return "|" + "|".join(f" {c} " if str(c) else " " for c in cells) + "|"


def table(header, rows):
    """Markdown table lines: a header line, the `|---|` line, one line per row (cells are
    strings, or values printed with str())."""
    return [table_row(header), "|" + "---|" * len(header)] + [table_row(row) for row in rows]


def _markers(name):
    return f"<!-- generated:{name} begin -->", f"<!-- generated:{name} end -->"


def replace_blocks(text, blocks):
    """text with the body of each block in blocks (name -> str or list of lines) replaced.
    Raises KeyError naming a block the text lacks: the page's prose decides where a block goes."""
    for name, body in blocks.items():
        if isinstance(body, (list, tuple)):
            body = "\n".join(body)
        begin, end = _markers(name)
        pattern = re.compile(re.escape(begin) + r"\n.*?" + re.escape(end), re.S)
        if not pattern.search(text):
            raise KeyError(f"no block '{name}' ({begin} ... {end}) in the page")
        body = body.strip("\n")
        text = pattern.sub(lambda _: f"{begin}\n{body}\n{end}" if body else f"{begin}\n{end}",
                           text, count=1)
    return text


def update_page(path, blocks):
    """Rewrites the named generated blocks of the page at path in place."""
    with open(path) as f:
        text = f.read()
    new = replace_blocks(text, blocks)
    if new != text:
        with open(path, "w") as f:
            f.write(new)
    print("updated", path, "blocks:", ", ".join(blocks))
