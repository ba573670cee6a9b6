"""Custom series: an expression of channels (``analysis.expression``) computed on a table's new rows as
they come, so it is plotted and binned like any channel (a ``Series`` whose ``derive`` is the expression).

Its names are the session's channels (``table.column``, or the bare column name where only one table
has it) and the quantities the live view derives (``ahf2_roll_deg``, ``onboard_roll_deg``, ``gyr_x_dps``
...: the names its Attitude and Sensors curves carry), and the same of each session beside the window's
after its name and a colon, as the Channels tab lists them (``S2:imu.gyr_x_rad_s``, ``S2:ahf2_roll_deg``;
``expression.SESSION_COLON``), their times on the window's axis (``session.timeline``). The rows are
those of the first name's table; a name of another table takes that table's newest row at or before
each row's time (``expression.at_or_before``). Each computation has a time budget (``BUDGET_S``); the dialog tries an
expression once on the session's latest rows (``try_on_latest_rows``) before taking it. No Qt here.
"""

from __future__ import annotations

import math

import numpy as np

from groundstation.analysis.expression import Expression, ExpressionError, at_or_before
from groundstation.session.view import ProductView
from groundstation.ui.series import Derive, imu_quantities, onboard_quantities
from groundstation.ui.session_series import Other, ShiftedTable

CUSTOM = "custom"  # the channels' "table" of custom series: "custom.NAME"
BUDGET_S = 0.5  # per computation (a redraw's new rows, or all rows at the first): past it the series is disabled
SAMPLE_ROWS = 500  # the dialog's trial: the latest rows of the expression's table


def expression_sources(view: ProductView, others: list[Other] = ()) -> dict[str, tuple[str, str, Derive | None]]:
    """Every name an expression may use: (its table, its column or derived quantity, the derive or None);
    those of ``others`` (the sessions beside the window's) after their name ("S2:imu.gyr_x_rad_s", of table "S2:imu")."""
    sources = own_sources(view)
    for other in others:
        sources.update({f"{other.label}:{name}": (other.name(table), key, derive)
                        for name, (table, key, derive) in own_sources(other.session.view).items()})
    return sources


def expression_tables(view: ProductView, lock, others: list[Other] = ()) -> dict[str, tuple]:
    """Each table of ``expression_sources``: (the table, the lock its session's reader writes it under);
    another session's with its times on the window's axis."""
    tables = {name: (table, lock) for name, table in view.tables.items() if table is not None}
    for other in others:
        tables.update({other.name(name): (ShiftedTable(table, other.offset_s), other.session.lock)
                       for name, table in other.session.view.tables.items() if table is not None})
    return tables


def own_sources(view: ProductView) -> dict[str, tuple[str, str, Derive | None]]:
    """``expression_sources`` of one session."""
    sources: dict[str, tuple[str, str, Derive | None]] = {}
    bare: dict[str, list[tuple[str, str, None]]] = {}
    for table, column in view.catalogue.channels():
        sources[f"{table.name}.{column.name}"] = (table.name, column.name, None)
        bare.setdefault(column.name, []).append((table.name, column.name, None))
    sources.update({name: places[0] for name, places in bare.items() if len(places) == 1})
    derived = [("onboard", onboard_quantities)] + ([("imu", imu_quantities(view.filters))] if view.filters else [])
    for table, derive in derived:
        columns = view.tables[table].columns
        for key in derive(np.full((1, len(columns)), math.nan), columns):  # the names it yields, from a row of NaN
            sources.setdefault(key, (table, key, derive))
    return sources


class _Rows:
    """What one table contributes to an expression, from its rows: raw columns and derived quantities."""

    def __init__(self, wanted: dict[str, tuple[str, Derive | None]]):
        self.wanted = wanted  # expression name -> (column or quantity, derive or None)

    def values(self, rows: np.ndarray, columns: tuple[str, ...]) -> dict[str, np.ndarray]:
        derived: dict[int, dict[str, np.ndarray]] = {}
        out = {}
        for name, (key, derive) in self.wanted.items():
            if derive is None:
                out[name] = rows[:, columns.index(key)]
            else:
                out[name] = derived.setdefault(id(derive), derive(rows, columns))[key]
        return out


class Sampler(_Rows):
    """Another table's contribution on the expression's times: its newest row at or before each."""

    def __init__(self, table, lock, wanted):
        super().__init__(wanted)
        self.table, self.lock = table, lock
        self.taken = 0
        self.time_s = np.empty(0)
        self.kept: dict[str, np.ndarray] = {name: np.empty(0) for name in wanted}

    def at(self, time_s: np.ndarray) -> dict[str, np.ndarray]:
        with self.lock:
            new = len(self.table) - self.taken
            rows = self.table.tail(new) if new > 0 else None
            self.taken += max(new, 0)
        if rows is not None and len(rows):
            fresh = self.values(rows, self.table.columns)
            self.time_s = np.concatenate([self.time_s, rows[:, self.table.columns.index("time_s")]])
            self.kept = {name: np.concatenate([self.kept[name], fresh[name]]) for name in self.kept}
        out = {name: at_or_before(time_s, self.time_s, values) for name, values in self.kept.items()}
        if len(time_s) and len(self.time_s):  # later times need only the row at or before the newest asked
            first = max(int(np.searchsorted(self.time_s, time_s[-1], side="right")) - 1, 0)
            self.time_s = self.time_s[first:]
            self.kept = {name: values[first:] for name, values in self.kept.items()}
        return out


class ExpressionDerive(_Rows):
    """``Series``' derive of a custom series ``name``: ``expression`` on the rows of its first name's
    table (``table``), the other tables' names sampled (``Sampler``); ``tables``: ``expression_tables``."""

    def __init__(self, name: str, expression: Expression, sources, tables: dict, budget_s: float = BUDGET_S):
        self.name, self.budget_s = name, budget_s
        self.expression = expression
        by_table: dict[str, dict[str, tuple[str, Derive | None]]] = {}
        for used in expression.names:
            table, key, derive = sources[used]
            by_table.setdefault(table, {})[used] = (key, derive)
        self.table = sources[expression.names[0]][0] if expression.names else "imu"
        super().__init__(by_table.pop(self.table, {}))
        self.samplers = [Sampler(*tables[table], wanted) for table, wanted in by_table.items()]

    def inputs(self, rows: np.ndarray, columns: tuple[str, ...]) -> dict[str, np.ndarray]:
        """The value of each name of the expression at these rows."""
        time_s = rows[:, columns.index("time_s")]
        values = self.values(rows, columns)
        for sampler in self.samplers:
            values.update(sampler.at(time_s))
        return values

    def result(self, values: dict[str, np.ndarray], count: int) -> np.ndarray:
        """The expression on ``inputs``' values, one per row (ExpressionError past the time budget)."""
        return np.broadcast_to(self.expression.evaluate(values, self.budget_s), (count,))

    def __call__(self, rows: np.ndarray, columns: tuple[str, ...]) -> dict[str, np.ndarray]:
        return {self.name: self.result(self.inputs(rows, columns), len(rows))}


def try_on_latest_rows(expression: Expression, sources, tables: dict, rows: int = SAMPLE_ROWS) -> None:
    """The expression computed once on its table's latest ``rows``, as a plot would: an ExpressionError
    if it cannot be, or if every row where its channels all have values gives it none (inf or NaN)."""
    derive = ExpressionDerive("trial", expression, sources, tables)
    table, lock = tables[derive.table]
    with lock:
        sample = table.tail(min(len(table), rows))
    if not len(sample):
        return  # nothing received yet: the numbers-only parts were checked when parsed
    values = derive.inputs(sample, table.columns)
    result = derive.result(values, len(sample))
    valued = np.logical_and.reduce([np.isfinite(v) for v in values.values()]) if values else np.ones(len(sample), bool)
    if valued.any() and not np.isfinite(result[valued]).any():
        raise ExpressionError(f"it gives no finite value (only inf or NaN) on the latest {len(sample)} rows "
                              f"where its channels have values: nothing would be drawn")
