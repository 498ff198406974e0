#!/usr/bin/env python3
"""Holds the Grafana dashboard (packaging/grafana/drivegate.json) to what it must be and to what the
daemon exports:

    check_grafana.py DASHBOARD [METRICS]

Without METRICS: the JSON is a dashboard Grafana imports (a title, a uid, schemaVersion 36 or
later, panels on the 24-column grid with ids of their own), its data source is the `datasource`
variable (type datasource, of prometheus), an `instance` variable picks gateways of a fleet, and
every query of every panel is scoped to the chosen instances.

With METRICS (a /metrics document the daemon rendered, e.g. the e2e test's scrape): every metric
name in every query, panels and variables alike, is one the document has, and every label a
query matches on or groups by is one those metrics carry (or a target label Prometheus adds:
instance, job). The names are read from the queries with a small PromQL tokenizer; nothing is
listed by hand.

Prints each complaint and exits 1 if there is one. Run by ctest (Grafana.DashboardIsValid) and by
tests/e2e/metrics_e2e_test.cpp with the running daemon's metrics.
"""
import json
import re
import sys

TARGET_LABELS = {"instance", "job"}
KEYWORDS = {"and", "or", "unless", "bool", "atan2"}
GROUPING = {"by", "without", "on", "ignoring", "group_left", "group_right"}
AGGREGATIONS = {"sum", "min", "max", "avg", "group", "stddev", "stdvar", "count", "count_values",
                "bottomk", "topk", "quantile", "limitk", "limit_ratio"}
TOKEN = re.compile(r"""
    (?P<ws>\s+)
  | (?P<str>"(?:[^"\\]|\\.)*"|'(?:[^'\\]|\\.)*'|`[^`]*`)
  | (?P<range>\[[^\]]*\])
  | (?P<dur>\d+(?:ms|[smhdwy])(?:\d+(?:ms|[smhdwy]))*(?![A-Za-z0-9_:]))
  | (?P<num>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)
  | (?P<var>\$\{[^}]*\}|\$[A-Za-z_][A-Za-z0-9_]*)
  | (?P<ident>[A-Za-z_:][A-Za-z0-9_:]*)
  | (?P<op>=~|!~|!=|==|<=|>=|[-+*/%^<>=(){},@])
""", re.X)
SAMPLE_LABEL = re.compile(r'([A-Za-z_][A-Za-z0-9_]*)="((?:[^"\\]|\\.)*)"')


def tokens(expr):
    """[(kind, text)] of a PromQL expression, whitespace left out; raises ValueError."""
    out, at = [], 0
    while at < len(expr):
        m = TOKEN.match(expr, at)
        if not m:
            raise ValueError(f"cannot read PromQL at {expr[at:at + 20]!r}")
        if m.lastgroup != "ws":
            out.append((m.lastgroup, m.group()))
        at = m.end()
    return out


class Query:
    """What one PromQL expression uses: metric names, and labels matched or grouped on."""

    def __init__(self, expr):
        self.metrics = []        # names, in order
        self.matchers = []       # (metric or None, label)
        self.grouping = []       # labels of by / without / on / ignoring / group_*
        toks = tokens(expr)
        i = 0
        while i < len(toks):
            kind, text = toks[i]
            nxt = toks[i + 1][1] if i + 1 < len(toks) else None
            if kind == "ident" and text in GROUPING:
                i += 1
                if nxt == "(":
                    i += 1
                    while i < len(toks) and toks[i][1] != ")":
                        if toks[i][0] == "ident":
                            self.grouping.append(toks[i][1])
                        i += 1
                    i += 1
                continue
            if kind == "ident" and text == "offset":
                i += 2  # its duration
                continue
            if kind == "ident" and (text in KEYWORDS or text.lower() in ("inf", "nan")):
                i += 1
                continue
            if kind == "ident" and (nxt == "(" or (text in AGGREGATIONS and nxt in GROUPING)):
                i += 1  # a function or an aggregation
                continue
            metric = None
            if kind == "ident":
                metric = text
                self.metrics.append(text)
                i += 1
            if i < len(toks) and toks[i][1] == "{" and (kind == "ident" or text == "{"):
                i = self._matchers(toks, i + 1, metric)
                continue
            if kind != "ident":
                i += 1

    def _matchers(self, toks, i, metric):
        while i < len(toks) and toks[i][1] != "}":
            if toks[i][0] == "ident":
                label = toks[i][1]
                if label == "__name__" and metric is None and i + 2 < len(toks):
                    if toks[i + 1][1] != "=":
                        raise ValueError("name a metric, not a pattern of __name__")
                    self.metrics.append(toks[i + 2][1][1:-1])
                else:
                    self.matchers.append((metric, label))
                i += 3  # label, operator, string
                continue
            i += 1
        return i + 1


def exported(metrics_text):
    """{metric name: set of label names} of a text exposition (format 0.0.4)."""
    out = {}
    for line in metrics_text.splitlines():
        if line.startswith("# TYPE "):
            out.setdefault(line.split()[2], set())
        if not line or line.startswith("#"):
            continue
        name = re.match(r"[A-Za-z_:][A-Za-z0-9_:]*", line).group()
        labels = out.setdefault(name, set())
        if line[len(name):].startswith("{"):
            labels.update(m.group(1) for m in SAMPLE_LABEL.finditer(line[len(name):line.rfind("}")]))
    return out


def panels_of(dashboard):
    """Every panel, those inside rows too."""
    for p in dashboard.get("panels", []):
        yield p
        yield from p.get("panels", [])


def check_structure(d, complain):
    for key in ("title", "uid", "panels", "templating", "schemaVersion", "time"):
        if key not in d:
            complain(f"no {key!r}")
    if not isinstance(d.get("schemaVersion"), int) or d["schemaVersion"] < 36:
        complain(f"schemaVersion {d.get('schemaVersion')!r}: 36 or later (Grafana 9)")
    variables = {v.get("name"): v for v in d.get("templating", {}).get("list", [])}
    ds = variables.get("datasource")
    if not ds or ds.get("type") != "datasource" or ds.get("query") != "prometheus":
        complain("no `datasource` variable of type datasource, query prometheus")
    inst = variables.get("instance")
    if not inst or inst.get("type") != "query" or not (inst.get("multi") or inst.get("includeAll")):
        complain("no `instance` variable (a query, several gateways at once)")
    ids = set()
    for p in panels_of(d):
        title = p.get("title", "?")
        if p.get("id") in ids:
            complain(f"panel {title!r}: id {p.get('id')} twice")
        ids.add(p.get("id"))
        g = p.get("gridPos", {})
        if not all(isinstance(g.get(k), int) for k in "xywh") or g["x"] + g["w"] > 24:
            complain(f"panel {title!r}: gridPos {g} is not on the 24-column grid")
        if p.get("type") == "row":
            continue
        if p.get("datasource") != {"type": "prometheus", "uid": "${datasource}"}:
            complain(f"panel {title!r}: its data source is not ${{datasource}}")
        if not p.get("targets"):
            complain(f"panel {title!r}: no query")
        for t in p.get("targets", []):
            expr = t.get("expr", "")
            if not expr or not t.get("refId"):
                complain(f"panel {title!r}: a query without expr or refId")
            elif 'instance=~"$instance"' not in expr:
                complain(f"panel {title!r}: {expr!r} is not scoped to instance=~\"$instance\"")


def queries(d):
    """(where, expr, label or None) of every query: panels' targets, variables' label_values."""
    for p in panels_of(d):
        for t in p.get("targets", []):
            if t.get("expr"):
                yield f"panel {p.get('title')!r}", t["expr"], None
    for v in d.get("templating", {}).get("list", []):
        if v.get("type") != "query":
            continue
        q = v.get("query")
        q = q.get("query", "") if isinstance(q, dict) else q or ""
        m = re.fullmatch(r"\s*label_values\((.*),\s*([A-Za-z_][A-Za-z0-9_]*)\s*\)\s*", q)
        if not m:
            yield f"variable {v.get('name')!r}", q, None
        else:
            yield f"variable {v.get('name')!r}", m.group(1), m.group(2)


def check_metrics(d, have, complain):
    names = set()
    for where, expr, label in queries(d):
        try:
            q = Query(expr)
        except ValueError as e:
            complain(f"{where}: {expr!r}: {e}")
            continue
        if not q.metrics:
            complain(f"{where}: {expr!r} names no metric")
        for m in q.metrics:
            names.add(m)
            if m not in have:
                complain(f"{where}: {m} is not among the daemon's metrics")
        carried = set(TARGET_LABELS)
        for m in q.metrics:
            carried |= have.get(m, set())
        for metric, l in q.matchers:
            labels = have.get(metric, set()) | TARGET_LABELS if metric else carried
            if l not in labels and (metric is None or metric in have):
                complain(f"{where}: {metric or ''}{{{l}...}}: no such label")
        for l in q.grouping + ([label] if label else []):
            if l not in carried:
                complain(f"{where}: {expr!r}: label {l} is on none of its metrics")
    return names


def main(argv):
    if len(argv) not in (2, 3):
        print(__doc__, file=sys.stderr)
        return 2
    problems = []

    def complain(msg):
        problems.append(msg)
        print(f"check_grafana: {argv[1]}: {msg}")

    with open(argv[1], encoding="utf-8") as f:
        d = json.load(f)
    check_structure(d, complain)
    names = set()
    if len(argv) == 3:
        with open(argv[2], encoding="utf-8") as f:
            names = check_metrics(d, exported(f.read()), complain)
    panels = sum(1 for p in panels_of(d) if p.get("type") != "row")
    what = f", {len(names)} metric names" if len(argv) == 3 else ""
    print(f"check_grafana: {panels} panels{what}: {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
