"""`rostool graph -o FILE`: the node/topic graph drawn to SVG, PNG or PDF without Graphviz.

Why networkx + matplotlib: Graphviz's `dot` binary cannot be a requirement, and the pip "graphviz"/pydot
packages only drive that binary. networkx (pure Python, maintained) does the graph work: breaking cycles
and the longest-path layering that makes dot's left-to-right flow; matplotlib (wheels everywhere) renders
the same figure to vector and raster formats, keeping names as SVG text. The few lines between them
(column order by barycenters, sizes) are ours.
"""

from __future__ import annotations

from pathlib import Path
from statistics import mean
from typing import Any

from rostool.output.graph_model import RosGraph
from rostool.output.graph_text import edges
from rostool.output.plot_deps import need

CHAR_W, ROW_H, GAP_W = 0.075, 0.42, 0.7  # inches at 9 pt
STYLE = {
    "n": {"boxstyle": "round,pad=0.35", "facecolor": "#e8f0fe", "edgecolor": "#3b6fc4"},
    "t": {"boxstyle": "square,pad=0.35", "facecolor": "#fff6dc", "edgecolor": "#b08a1e"},
    "s": {"boxstyle": "sawtooth,pad=0.35", "facecolor": "#f5e6f7", "edgecolor": "#8a3b96"},
}


def layers(ids: list[str], links: list[tuple[str, str]]) -> list[list[str]]:
    """Columns left to right: sources first, each id after everything that feeds it (cycles broken)."""
    nx = need("networkx", "plot")
    graph = nx.DiGraph()
    graph.add_nodes_from(ids)
    graph.add_edges_from(links)
    dag = graph.copy()
    while True:
        try:
            cycle = nx.find_cycle(dag)
        except nx.NetworkXNoCycle:
            break
        dag.remove_edge(*cycle[-1][:2])
    columns = [sorted(generation) for generation in nx.topological_generations(dag)]
    # a few barycenter sweeps: place each id near the ids it connects to in the previous column
    for _ in range(4):
        for index in range(1, len(columns)):
            rank = {name: i for i, name in enumerate(columns[index - 1])}
            here = {name: i for i, name in enumerate(columns[index])}

            def key(name: str, rank: dict[str, int] = rank, here: dict[str, int] = here) -> float:
                around = [rank[p] for p in graph.predecessors(name) if p in rank]
                around += [rank[s] for s in graph.successors(name) if s in rank]
                return mean(around) if around else float(here[name])

            columns[index].sort(key=key)
    return columns


def draw(graph: RosGraph, path: Path) -> None:
    """Write the graph to `path`; the format is the file's suffix (svg, png, pdf)."""
    mpl = need("matplotlib", "plot")
    mpl.use("Agg")
    import matplotlib.pyplot as plt

    ids = [*("n:" + n for n in graph.nodes), *("t:" + t.name for t in graph.topics)]
    ids += ["s:" + s.name for s in graph.services]
    links = edges(graph)
    columns = layers(ids, links)
    widths = [max((len(name) - 2) * CHAR_W for name in column) + 0.3 for column in columns] or [1.0]
    rows = max((len(column) for column in columns), default=1)
    width = sum(widths) + GAP_W * (len(widths) + 1)
    height = rows * ROW_H * 1.6 + 0.6
    with mpl.rc_context({"svg.fonttype": "none", "font.size": 9}):
        fig = plt.figure(figsize=(max(width, 3.0), max(height, 1.5)))
        ax = fig.add_axes((0, 0, 1, 1))
        ax.set_xlim(0, max(width, 3.0))
        ax.set_ylim(0, max(height, 1.5))
        ax.set_axis_off()
        texts: dict[str, Any] = {}
        left = GAP_W
        for column, column_width in zip(columns, widths, strict=False):
            x = left + column_width / 2
            step = (max(height, 1.5)) / (len(column) + 1)
            for i, name in enumerate(column):
                y = max(height, 1.5) - step * (i + 1)
                texts[name] = ax.text(x, y, name[2:], ha="center", va="center", zorder=2,
                                      bbox=STYLE[name[0]], gid=name)  # fmt: skip
            left += column_width + GAP_W
        column_of = {name: i for i, column in enumerate(columns) for name in column}
        for source, target in links:
            a, b = texts[source], texts[target]
            # neighbours get straight arrows; longer and backward ones bend, so they do not cross boxes
            bend = 0.0 if column_of[target] - column_of[source] == 1 else 0.25
            ax.annotate(
                "", xy=b.get_position(), xytext=a.get_position(), zorder=3,
                arrowprops={"arrowstyle": "-|>", "color": "0.35", "shrinkA": 1, "shrinkB": 1,
                            "patchA": a.get_bbox_patch(), "patchB": b.get_bbox_patch(),
                            "connectionstyle": f"arc3,rad={bend}"},
            )  # fmt: skip
        try:
            fig.savefig(path, dpi=150)
        finally:
            plt.close(fig)
