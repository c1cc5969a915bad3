"""Function objects: sampling attached to a run (``system/controlDict`` ``functions {}``).

Output goes to ``postProcessing/<name>/<startTime>/<name>.dat`` with a ``#`` header, as
OpenFOAM writes it; a run restarted from a later time writes a new ``<startTime>`` folder.
"""

from __future__ import annotations

import abc
from pathlib import Path
from typing import Literal

from pydantic import Field

from sphfoam.engine.schedule import Schedule
from sphfoam.registry import Coeffs, Model


class FunctionObjectCoeffs(Coeffs):
    writeControl: Literal["timeStep", "runTime", "writeTime"] = "timeStep"
    writeInterval: float = Field(1, gt=0)


class FunctionObject(Model, abc.ABC):
    family = "functionObject"
    object_name: str = ""
    columns: tuple[str, ...] = ()
    #: the case dimensions it samples (a 3-D case refuses one without 3 by name)
    dims: tuple[int, ...] = (2,)
    #: further ``#`` header lines written before the column names (e.g. where sensors read)
    notes: tuple[str, ...] = ()

    @property
    def header_doc(self) -> str:
        """What the output's first header line says the object records (its ``doc``)."""
        return self.doc

    def start(self, case, ctx, start_time_name: str) -> None:
        self.case, self.ctx = case, ctx
        self.folder = Path(case.path) / "postProcessing" / self.object_name / start_time_name
        self.folder.mkdir(parents=True, exist_ok=True)
        self.file = self.folder / f"{self.object_name}.dat"
        self._fh = self.file.open("w")
        self._fh.write(f"# {self.name}: {self.header_doc}\n"
                       + "".join(f"# {n}\n" for n in self.notes)
                       + "# " + "\t".join(self.columns) + "\n")

    @property
    def schedule(self) -> Schedule:
        """When this function object samples during a run: every writeInterval steps of the
        run's step index, whenever the time crosses a multiple of writeInterval, or at
        time-directory writes; the same steps and times after a restart."""
        c = self.coeffs
        return Schedule(c.writeControl, c.writeInterval)

    def due(self, sim, wrote: bool, previous_time: float | None = None) -> bool:
        """Whether the step that took ``sim`` from ``previous_time`` (by default, the time
        before its last step) samples."""
        if previous_time is None:
            previous_time = sim.time - sim.last_dt
        return self.schedule.due(sim.step_index, sim.time, previous_time, wrote)

    def write_row(self, values) -> None:
        self._fh.write("\t".join(f"{v:.9g}" for v in values) + "\n")
        self._fh.flush()

    @abc.abstractmethod
    def execute(self, sim) -> None:
        """Sample the current state and write a row."""

    def end(self) -> None:
        self._fh.close()
