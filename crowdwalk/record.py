"""The run folder: :class:`RunWriter` writes it while a simulation runs, :func:`open_run`
reads it back.

Layout (docs/architecture.md, "Run folder"):

- ``scenario.yaml`` — the scenario as run.
- ``trajectories.sqlite`` — JuPedSim SQLite trajectory format version 2
  (``trajectory_data``, ``metadata``, ``geometry``, ``frame_data``), which PedPy's
  ``load_trajectory_from_jupedsim_sqlite`` / ``load_walkable_area_from_jupedsim_sqlite``
  read unchanged, plus ``trajectory_z(frame, id, pos_z)`` for heights [m].
- ``footsteps.csv`` — one row per foot placement.
- ``poses.sqlite`` — ``skeleton``, ``agents``, ``pose_frame`` with little-endian blobs.
- ``summary.json`` — per agent and per group statistics and run timing.

Every table is committed by :meth:`RunWriter.flush`; the simulation calls it at least once
per simulated second, so a run that is interrupted (Ctrl-C, kill) stays readable up to the
last flush. SQLite's journal makes a killed writer's last transaction vanish cleanly.
The index ``frame_id_idx`` on ``trajectory_data(frame, id)`` is built by
:meth:`RunWriter.close` (a finished or interrupted run); a killed run's file has none and
reads the same.
"""

from __future__ import annotations

import csv
import json
import sqlite3
import zlib
from collections.abc import Sequence
from contextlib import closing
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from crowdwalk.csv_text import rows_text
from crowdwalk.errors import InputError, invalid
from crowdwalk.steps import FOOTSTEP_COLUMNS, FootstepTable, StepBatch

__all__ = [
    "FOOTSTEP_COLUMNS",
    "FootstepTable",
    "RunWriter",
    "Run",
    "Trajectories",
    "Poses",
    "PoseRecord",
    "WalkableAreas",
    "open_run",
]

_TRAJECTORY_SCHEMA = """
CREATE TABLE IF NOT EXISTS metadata(key TEXT NOT NULL UNIQUE PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS geometry(hash INTEGER NOT NULL UNIQUE PRIMARY KEY, wkt TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS frame_data(frame INTEGER NOT NULL, geometry_hash INTEGER NOT NULL);
CREATE TABLE IF NOT EXISTS trajectory_data(
    frame INTEGER NOT NULL, id INTEGER NOT NULL,
    pos_x REAL NOT NULL, pos_y REAL NOT NULL, ori_x REAL NOT NULL, ori_y REAL NOT NULL);
CREATE TABLE IF NOT EXISTS trajectory_z(frame INTEGER NOT NULL, id INTEGER NOT NULL,
    pos_z REAL NOT NULL);
"""

# built when the writer closes (after a Ctrl-C too), not row by row during the run: it cost
# a third of every insert. A killed run's file has no index and reads the same, unsorted
# rows sorted by the readers' ORDER BY.
_TRAJECTORY_INDEX = "CREATE INDEX IF NOT EXISTS frame_id_idx ON trajectory_data(frame, id)"

# rows per INSERT statement: one multi-row ``VALUES`` statement binds its parameters in one
# C loop and steps once, against a statement step per row with ``executemany`` over rows
# (16 ms instead of 48 ms per 10,000-walker frame, trajectory_data and trajectory_z; 50,
# 200 and 1,000 rows a statement cost about the same). 6 x 160 = 960 parameters: SQLite
# before 3.32 allows 999 a statement.
_ROWS_PER_INSERT = 160

_POSE_SCHEMA = """
CREATE TABLE IF NOT EXISTS skeleton(joint INTEGER PRIMARY KEY, name TEXT NOT NULL,
    parent INTEGER NOT NULL);
CREATE TABLE IF NOT EXISTS agents(id INTEGER PRIMARY KEY, body_height REAL NOT NULL,
    grp TEXT NOT NULL, planner TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS pose_meta(key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS pose_frame(frame INTEGER PRIMARY KEY, time REAL NOT NULL,
    ids BLOB NOT NULL, root BLOB NOT NULL, joints BLOB NOT NULL, positions BLOB NOT NULL,
    contact BLOB NOT NULL, fallback BLOB NOT NULL);
"""


#: characters that make csv.writer (QUOTE_MINIMAL) quote a field
_CSV_SPECIAL = ',"\r\n'


def _blob(array: np.ndarray, dtype: str) -> bytes:
    return np.ascontiguousarray(array, dtype=dtype).tobytes()


@lru_cache(maxsize=64)
def _insert_sql(table: str, columns: int, rows: int) -> str:
    row = "(" + ",".join("?" * columns) + ")"
    return f"INSERT INTO {table} VALUES " + ",".join([row] * rows)


def _insert_rows(con: sqlite3.Connection, table: str, columns: Sequence[list]) -> None:
    """Append rows to ``table``: ``columns`` (m lists of k values, in the table's column
    order), row i = the i-th value of each; rows keep their order."""
    m, k = len(columns), len(columns[0])
    flat: list = [None] * (m * k)
    for c, values in enumerate(columns):
        flat[c::m] = values
    width = m * _ROWS_PER_INSERT
    full = k // _ROWS_PER_INSERT * width
    if full:
        con.executemany(_insert_sql(table, m, _ROWS_PER_INSERT),
                        [flat[j:j + width] for j in range(0, full, width)])
    if full < len(flat):
        con.execute(_insert_sql(table, m, (len(flat) - full) // m), flat[full:])


class RunWriter:
    """Write a run folder incrementally; a :class:`crowdwalk.sinks.RunSink`.

    Parameters
    ----------
    out : path
        Run folder; created if missing. Existing run files in it are replaced.
    scenario_text : str
        The scenario YAML as run (copied to ``scenario.yaml``).
    walkable_wkt : str
        Walkable area as WKT [m] (stored in the trajectory file's ``geometry`` table).
    fps : float
        Output frame rate of trajectories and poses [1/s].
    skeleton : (names, parents) or None
        Joint names (J,) and parent indices (J,) (-1 for the root); ``None`` writes no
        ``poses.sqlite``.
    """

    def __init__(
        self,
        out: str | Path,
        *,
        scenario_text: str,
        walkable_wkt: str,
        fps: float,
        skeleton: tuple[Sequence[str], Sequence[int]] | None = None,
    ) -> None:
        if not np.isfinite(fps) or fps <= 0:
            raise invalid("RunWriter", "fps", "a positive frame rate [1/s]", fps)
        self.path = Path(out)
        self.path.mkdir(parents=True, exist_ok=True)
        for name in ("trajectories.sqlite", "poses.sqlite", "footsteps.csv", "summary.json"):
            (self.path / name).unlink(missing_ok=True)
        (self.path / "scenario.yaml").write_text(scenario_text)
        self.fps = float(fps)

        self._traj = sqlite3.connect(self.path / "trajectories.sqlite")
        self._traj.executescript(_TRAJECTORY_SCHEMA)
        self._geometry_hash = zlib.crc32(walkable_wkt.encode())
        self._traj.execute(
            "INSERT INTO geometry(hash, wkt) VALUES (?, ?)", (self._geometry_hash, walkable_wkt)
        )
        self._meta: dict[str, str] = {"version": "2", "fps": repr(self.fps)}
        self._bounds = np.array([np.inf, np.inf, -np.inf, -np.inf])
        self._write_metadata()

        self._steps_file = open(self.path / "footsteps.csv", "w", newline="")  # noqa: SIM115
        self._steps = csv.writer(self._steps_file)
        self._steps.writerow(FOOTSTEP_COLUMNS)

        self._poses: sqlite3.Connection | None = None
        if skeleton is not None:
            names, parents = skeleton
            self._poses = sqlite3.connect(self.path / "poses.sqlite")
            self._poses.executescript(_POSE_SCHEMA)
            self._poses.executemany(
                "INSERT INTO skeleton(joint, name, parent) VALUES (?, ?, ?)",
                [(j, str(n), int(p)) for j, (n, p) in enumerate(zip(names, parents, strict=True))],
            )
            self._poses.execute("INSERT INTO pose_meta VALUES ('fps', ?)", (repr(self.fps),))
        self.flush()

    # --- the RunSink protocol ---------------------------------------------------------

    def begin(self, info) -> None:
        """Describe the run's agents (``crowdwalk.sinks.RunInfo``) in ``poses.sqlite``."""
        self.write_agents(np.arange(len(info)), info.body_height, list(info.group),
                          list(info.planner))

    def steps(self, batch: StepBatch) -> None:
        """Append the footsteps of a :class:`~crowdwalk.steps.StepBatch`."""
        self.write_footsteps(batch.footstep_columns())

    def set_walkable(self, walkable_wkt: str) -> None:
        """From the next frame on, the walkable area is ``walkable_wkt`` (a door shut or
        opened): JuPedSim v2's ``frame_data`` names each frame's geometry."""
        self._geometry_hash = zlib.crc32(walkable_wkt.encode())
        self._traj.execute("INSERT OR IGNORE INTO geometry(hash, wkt) VALUES (?, ?)",
                           (self._geometry_hash, walkable_wkt))

    def frame(self, time: float, snapshot, poses) -> None:
        """Append one output frame (a ``crowdwalk.sinks.Snapshot``) and its poses (a
        ``crowdwalk.gait.engine.PoseFrame`` or None); commit once per simulated second."""
        s = snapshot
        self.write_frame(s.frame, s.agents, s.xy, s.z, s.orientation)
        if poses is not None:
            self.write_pose(s.frame, time, poses.agents, poses.root_position,
                            poses.root_quaternion, poses.joints, poses.positions,
                            poses.contact, poses.fallback)
        if s.frame > 0 and s.frame % max(1, int(round(self.fps))) == 0:
            self.flush()

    def end(self, summary: dict) -> None:
        """Write ``summary.json`` and close the files."""
        self.write_summary(summary)
        self.close()

    # --- trajectories ---------------------------------------------------------------

    def write_frame(
        self,
        frame: int,
        ids: np.ndarray,
        xy: np.ndarray,
        z: np.ndarray,
        orientation: np.ndarray,
    ) -> None:
        """Append one output frame.

        Parameters
        ----------
        frame : int
            Frame number (time = frame / fps [s]).
        ids : (k,) int
            Agent ids present in the frame.
        xy : (k, 2) float
            Positions [m].
        z : (k,) float
            Ground heights under the agents [m].
        orientation : (k, 2) float
            Unit walking directions.
        """
        ids = np.asarray(ids, dtype=np.int64)
        self._traj.execute(
            "INSERT INTO frame_data(frame, geometry_hash) VALUES (?, ?)",
            (int(frame), self._geometry_hash),
        )
        if ids.size == 0:
            return
        xy = np.asarray(xy, dtype=float)
        orientation = np.asarray(orientation, dtype=float)
        z = np.asarray(z, dtype=float)
        if xy.shape != (ids.size, 2) or orientation.shape != xy.shape or z.shape != ids.shape:
            raise invalid("RunWriter", "frame", f"ids (k,), xy (k, 2), z (k,), orientation "
                          f"(k, 2) with k = {ids.size}",
                          f"{xy.shape}, {z.shape}, {orientation.shape}")
        frames, agent = [int(frame)] * ids.size, ids.tolist()
        _insert_rows(self._traj, "trajectory_data", (
            frames, agent, xy[:, 0].tolist(), xy[:, 1].tolist(), orientation[:, 0].tolist(),
            orientation[:, 1].tolist()))
        _insert_rows(self._traj, "trajectory_z", (frames, agent, z.tolist()))
        lo = xy.min(axis=0)
        hi = xy.max(axis=0)
        self._bounds = np.array(
            [min(self._bounds[0], lo[0]), min(self._bounds[1], lo[1]),
             max(self._bounds[2], hi[0]), max(self._bounds[3], hi[1])]
        )

    def _write_metadata(self) -> None:
        meta = dict(self._meta)
        if np.all(np.isfinite(self._bounds)):
            meta.update(
                xmin=repr(float(self._bounds[0])), ymin=repr(float(self._bounds[1])),
                xmax=repr(float(self._bounds[2])), ymax=repr(float(self._bounds[3])),
            )
        self._traj.executemany(
            "INSERT OR REPLACE INTO metadata(key, value) VALUES (?, ?)", meta.items()
        )

    # --- footsteps ------------------------------------------------------------------

    def write_footsteps(self, rows) -> None:
        """Append foot placements.

        Parameters
        ----------
        rows : FootstepTable, or a mapping of column name -> (k,) array
            Every column of :data:`FOOTSTEP_COLUMNS` (units in :class:`FootstepTable`).
        """
        if isinstance(rows, FootstepTable):
            rows = rows.columns()
        missing = [c for c in FOOTSTEP_COLUMNS if c not in rows]
        if missing:
            raise invalid("RunWriter", "footsteps", f"a table with columns {missing}", sorted(rows))
        text = rows_text([rows[c] for c in FOOTSTEP_COLUMNS])  # compiled, nogil
        if text is not None:
            if text:
                self._steps_file.write(text.decode("ascii"))
            return
        columns, plain = [], True
        for c in FOOTSTEP_COLUMNS:
            col = np.asarray(rows[c])
            if col.dtype.kind == "f":
                col = np.round(col, 5)
            elif col.dtype.kind not in "iub":  # text: plain unless csv would quote it
                plain &= col.dtype.kind == "U" and not any(
                    ch in "".join(col.tolist()) for ch in _CSV_SPECIAL)
            columns.append(col.tolist())
        if len({len(col) for col in columns}) > 1:
            raise invalid("RunWriter", "footsteps", "columns of one length",
                          {c: len(col) for c, col in zip(FOOTSTEP_COLUMNS, columns, strict=True)})
        if not plain:
            self._steps.writerows(zip(*columns, strict=True))
        elif columns[0]:  # csv.writer's text, a third cheaper than its row-by-row writes
            text = [list(map(str, col)) for col in columns]
            self._steps_file.write("\r\n".join(map(",".join, zip(*text, strict=True))) + "\r\n")

    # --- poses ----------------------------------------------------------------------

    @property
    def records_poses(self) -> bool:
        """True when this writer stores poses."""
        return self._poses is not None

    def write_agents(
        self, ids: np.ndarray, body_heights: np.ndarray, groups: Sequence[str],
        planners: Sequence[str],
    ) -> None:
        """Describe agents in ``poses.sqlite`` (ids (k,), body heights (k,) [m])."""
        if self._poses is None:
            return
        self._poses.executemany(
            "INSERT OR REPLACE INTO agents(id, body_height, grp, planner) VALUES (?, ?, ?, ?)",
            zip(np.asarray(ids).tolist(), np.asarray(body_heights, float).tolist(),
                list(groups), list(planners), strict=True),
        )

    def write_pose(
        self,
        frame: int,
        time: float,
        ids: np.ndarray,
        root_position: np.ndarray,
        root_quaternion: np.ndarray,
        joints: np.ndarray,
        positions: np.ndarray,
        contact: np.ndarray,
        fallback: np.ndarray,
    ) -> None:
        """Append one pose frame: ids (k,), root position (k,3) [m], root quaternion (k,4)
        wxyz, local joint quaternions (k,J,4), joint world positions (k,J,3) [m], foot
        contact (k,2) bool, fallback (k,) bool."""
        if self._poses is None:
            return
        root = np.concatenate([np.asarray(root_position), np.asarray(root_quaternion)], axis=1)
        self._poses.execute(
            "INSERT INTO pose_frame VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
            (
                int(frame), float(time), _blob(ids, "<i4"), _blob(root, "<f4"),
                _blob(joints, "<f4"), _blob(positions, "<f4"), _blob(contact, "u1"),
                _blob(fallback, "u1"),
            ),
        )

    # --- summary and lifetime -------------------------------------------------------

    def write_summary(self, summary: dict) -> None:
        """Write ``summary.json`` atomically (a reader never sees half a file)."""
        tmp = self.path / "summary.json.tmp"
        tmp.write_text(json.dumps(summary, indent=1, allow_nan=False, default=_jsonable))
        tmp.replace(self.path / "summary.json")

    def flush(self) -> None:
        """Commit everything written so far to disk."""
        self._write_metadata()
        self._traj.commit()
        self._steps_file.flush()
        if self._poses is not None:
            self._poses.commit()

    def close(self) -> None:
        """Flush, index the trajectory rows by frame and id, and close all files."""
        self.flush()
        self._traj.execute(_TRAJECTORY_INDEX)
        self._traj.commit()
        self._traj.close()
        self._steps_file.close()
        if self._poses is not None:
            self._poses.close()

    def __enter__(self) -> RunWriter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _jsonable(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


# --- reading --------------------------------------------------------------------------


def _connect(path: Path) -> sqlite3.Connection:
    """Open a run database for reading. Read-only when possible; a database left with a
    hot rollback journal by a killed writer is opened normally so that SQLite rolls the
    unfinished transaction back (the state of the last flush)."""
    con = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
    try:
        con.execute("SELECT count(*) FROM sqlite_master").fetchone()
        return con
    except sqlite3.OperationalError:
        con.close()
        return sqlite3.connect(path)


@dataclass(frozen=True)
class Trajectories:
    """All trajectory rows, struct-of-arrays (n rows): frame (n,), id (n,), x, y, z (n,)
    [m], ori_x, ori_y (n,) unit direction; fps [1/s]. Sorted by frame then id."""

    frame: np.ndarray
    id: np.ndarray
    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    ori_x: np.ndarray
    ori_y: np.ndarray
    fps: float

    @property
    def time(self) -> np.ndarray:
        """Row times (n,) [s]."""
        return self.frame / self.fps

    def agent(self, agent_id: int) -> Trajectories:
        """The rows of one agent."""
        keep = self.id == agent_id
        return Trajectories(
            *(getattr(self, f)[keep] for f in ("frame", "id", "x", "y", "z", "ori_x", "ori_y")),
            fps=self.fps,
        )


@dataclass(frozen=True)
class PoseRecord:
    """One stored pose frame for k agents: time [s], ids (k,), root position (k,3) [m],
    root quaternion (k,4) wxyz, local joint quaternions (k,J,4), joint world positions
    (k,J,3) [m], contact (k,2) bool, fallback (k,) bool."""

    frame: int
    time: float
    ids: np.ndarray
    root_position: np.ndarray
    root_quaternion: np.ndarray
    joints: np.ndarray
    positions: np.ndarray
    contact: np.ndarray
    fallback: np.ndarray


class Poses:
    """Reader of ``poses.sqlite``: ``names`` (J,), ``parents`` (J,), ``frames`` (F,),
    ``times`` (F,) [s], ``body_heights`` {id: m}; :meth:`frame` and :meth:`agent_track`."""

    def __init__(self, path: Path) -> None:
        self._con = _connect(path)
        rows = self._con.execute("SELECT name, parent FROM skeleton ORDER BY joint").fetchall()
        self.names = [r[0] for r in rows]
        self.parents = np.array([r[1] for r in rows], dtype=int)
        ft = self._con.execute("SELECT frame, time FROM pose_frame ORDER BY frame").fetchall()
        self.frames = np.array([r[0] for r in ft], dtype=int)
        self.times = np.array([r[1] for r in ft], dtype=float)
        self.body_heights = dict(self._con.execute("SELECT id, body_height FROM agents"))
        fps = self._con.execute("SELECT value FROM pose_meta WHERE key='fps'").fetchone()
        self.fps = float(fps[0]) if fps else float("nan")

    def frame(self, frame: int) -> PoseRecord:
        """The stored pose of every agent in one output frame."""
        query = "SELECT * FROM pose_frame WHERE frame = ?"
        row = self._con.execute(query, (int(frame),)).fetchone()
        if row is None:
            raise invalid("Poses", "frame", f"a stored frame in {self.frames[:1]}..", frame)
        return self._decode(row)

    def _decode(self, row) -> PoseRecord:
        frame, time, ids, root, joints, positions, contact, fallback = row
        ids = np.frombuffer(ids, "<i4").astype(int)
        k, nj = ids.size, len(self.names)
        root = np.frombuffer(root, "<f4").reshape(k, 7).astype(float)
        return PoseRecord(
            frame=int(frame), time=float(time), ids=ids,
            root_position=root[:, :3], root_quaternion=root[:, 3:],
            joints=np.frombuffer(joints, "<f4").reshape(k, nj, 4).astype(float),
            positions=np.frombuffer(positions, "<f4").reshape(k, nj, 3).astype(float),
            contact=np.frombuffer(contact, "u1").reshape(k, 2).astype(bool),
            fallback=np.frombuffer(fallback, "u1").astype(bool),
        )

    def __iter__(self):
        for row in self._con.execute("SELECT * FROM pose_frame ORDER BY frame"):
            yield self._decode(row)

    def agent_track(self, agent_id: int) -> dict[str, np.ndarray]:
        """One agent's poses over time: ``time`` (F,) [s], ``root_position`` (F,3) [m],
        ``root_quaternion`` (F,4), ``joints`` (F,J,4), ``positions`` (F,J,3) [m],
        ``contact`` (F,2), over the frames where the agent is present."""
        out: dict[str, list] = {k: [] for k in
                                ("time", "root_position", "root_quaternion", "joints",
                                 "positions", "contact")}
        for rec in self:
            hit = np.flatnonzero(rec.ids == agent_id)
            if hit.size == 0:
                continue
            i = hit[0]
            out["time"].append(rec.time)
            for key in ("root_position", "root_quaternion", "joints", "positions", "contact"):
                out[key].append(getattr(rec, key)[i])
        if not out["time"]:
            raise invalid("Poses", "agent", "an agent id present in poses.sqlite", agent_id)
        return {k: np.asarray(v) for k, v in out.items()}

    def close(self) -> None:
        """Close the database."""
        self._con.close()


@dataclass(frozen=True, eq=False)
class WalkableAreas:
    """The walkable area over a run (doors shut and opened by events): area ``areas[k]``
    (shapely geometry [m]) holds from time ``start[k]`` [s] (g,) until ``start[k + 1]``;
    ``start`` increases, ``start[0]`` is the first frame's time. Read from JuPedSim v2's
    ``frame_data`` (each frame's geometry hash); a run whose area never changes has one."""

    start: np.ndarray
    areas: tuple

    def index(self, t: float) -> int:
        """The area current at time ``t`` [s] (the first one before the first frame)."""
        return max(int(np.searchsorted(self.start, t + 1e-9, side="right")) - 1, 0)

    def at(self, t: float):
        """The walkable area (shapely geometry [m]) current at time ``t`` [s]."""
        return self.areas[self.index(t)]


class Run:
    """A run folder opened for reading (see :func:`open_run`)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.scenario_path = path / "scenario.yaml"
        self.trajectory_path = path / "trajectories.sqlite"
        self.footsteps_path = path / "footsteps.csv"
        self.poses_path = path / "poses.sqlite"
        self.summary_path = path / "summary.json"

    @property
    def complete(self) -> bool:
        """Whether the run wrote ``summary.json`` (finished, or interrupted cleanly); a run
        killed outright (SIGKILL, power loss) has only what its last flush wrote."""
        return self.summary_path.exists()

    @property
    def summary(self) -> dict:
        """``summary.json`` as a dict (``{}`` when the run never wrote one)."""
        if not self.summary_path.exists():
            return {}
        return json.loads(self.summary_path.read_text())

    @property
    def fps(self) -> float:
        """Output frame rate [1/s]."""
        with closing(_connect(self.trajectory_path)) as con:
            return float(con.execute("SELECT value FROM metadata WHERE key='fps'").fetchone()[0])

    def trajectories(self) -> Trajectories:
        """All trajectory rows with heights, sorted by frame and id."""
        with closing(_connect(self.trajectory_path)) as con:
            fps = float(con.execute("SELECT value FROM metadata WHERE key='fps'").fetchone()[0])
            rows = con.execute(
                "SELECT t.frame, t.id, t.pos_x, t.pos_y, COALESCE(z.pos_z, 0.0), t.ori_x, t.ori_y "
                "FROM trajectory_data t LEFT JOIN trajectory_z z "
                "ON t.frame = z.frame AND t.id = z.id ORDER BY t.frame, t.id"
            ).fetchall()
        a = np.array(rows, dtype=float).reshape(-1, 7)
        return Trajectories(
            frame=a[:, 0].astype(int), id=a[:, 1].astype(int), x=a[:, 2], y=a[:, 3],
            z=a[:, 4], ori_x=a[:, 5], ori_y=a[:, 6], fps=fps,
        )

    def walkable_area(self):
        """The walkable area (shapely geometry) [m]."""
        import shapely

        with closing(_connect(self.trajectory_path)) as con:
            wkts = [r[0] for r in con.execute("SELECT wkt FROM geometry")]
        return shapely.union_all([shapely.from_wkt(w) for w in wkts])

    def walkable_areas(self) -> WalkableAreas:
        """The walkable area current at each frame, as its changes over time."""
        import shapely

        with closing(_connect(self.trajectory_path)) as con:
            fps = float(con.execute("SELECT value FROM metadata WHERE key='fps'").fetchone()[0])
            wkt = dict(con.execute("SELECT hash, wkt FROM geometry"))
            rows = con.execute("SELECT frame, geometry_hash FROM frame_data "
                               "ORDER BY frame").fetchall()
        if not rows:  # no frame written: the area the run started with
            return WalkableAreas(np.zeros(1), (self.walkable_area(),))
        start, hashes = [], []
        for frame, h in rows:  # a row per frame, once per run (no tick loop)
            if not hashes or h != hashes[-1]:
                start.append(frame / fps)
                hashes.append(h)
        return WalkableAreas(np.asarray(start, float),
                             tuple(shapely.from_wkt(wkt[h]) for h in hashes))

    def footsteps(self) -> FootstepTable:
        """``footsteps.csv`` as a :class:`~crowdwalk.steps.FootstepTable`. Rows of a partly
        written last line (an interrupted run) are dropped. Raises
        :class:`~crowdwalk.errors.InputError` (``footsteps.csv:1``) when a column is
        missing."""
        with open(self.footsteps_path, newline="") as fh:
            reader = csv.reader(fh)
            header = next(reader, [])
            rows = [r for r in reader if len(r) == len(header)]
        try:
            return FootstepTable.from_text(header, rows)
        except ValueError as exc:
            raise InputError(f"{self.footsteps_path}:1: footsteps header must hold every "
                             f"column of crowdwalk.steps.FOOTSTEP_COLUMNS; {exc}.") from None

    def poses(self) -> Poses | None:
        """The pose reader, or ``None`` when the run stored no poses."""
        if not self.poses_path.exists():
            return None
        return Poses(self.poses_path)


def open_run(path: str | Path) -> Run:
    """Open a run folder written by :class:`RunWriter`.

    Raises
    ------
    FileNotFoundError
        When the folder has no ``trajectories.sqlite``.
    """
    path = Path(path)
    if not (path / "trajectories.sqlite").exists():
        raise FileNotFoundError(str(path / "trajectories.sqlite"))
    return Run(path)
