"""Function objects: sampling attached to a run (``system/controlDict`` ``functions {}``).

Output goes to ``postProcessing/<name>/<startTime>/<name>.dat`` with a ``#`` header, as
OpenFOAM writes it; a run restarted from a later time writes a new ``<startTime>`` folder.
"""

from __future__ import annotations

import abc
from pathlib import Path
from typing import Literal

from pydantic import Field

from sphfoam.registry import Coeffs, Model


class FunctionObjectCoeffs(Coeffs):
    writeControl: Literal["timeStep", "runTime", "writeTime"] = "timeStep"
    writeInterval: float = Field(1, gt=0)


class FunctionObject(Model, abc.ABC):
    family = "functionObject"
    object_name: str = ""
    columns: tuple[str, ...] = ()

    def start(self, case, ctx, start_time_name: str) -> None:
        self.case, self.ctx = case, ctx
        self.folder = Path(case.path) / "postProcessing" / self.object_name / start_time_name
        self.folder.mkdir(parents=True, exist_ok=True)
        self.file = self.folder / f"{self.object_name}.dat"
        self._fh = self.file.open("w")
        self._fh.write(f"# {self.name}: {self.doc}\n# " + "\t".join(self.columns) + "\n")
        self._next = None
        self._steps = 0

    def due(self, sim, wrote: bool) -> bool:
        c = self.coeffs
        self._steps += 1
        if c.writeControl == "writeTime":
            return wrote
        if c.writeControl == "timeStep":
            return self._steps % int(c.writeInterval) == 0
        if self._next is None or sim.time >= self._next - 1e-12:
            self._next = (int(sim.time / c.writeInterval + 1e-9) + 1) * c.writeInterval
            return True
        return False

    def write_row(self, values) -> None:
        self._fh.write("\t".join(f"{v:.9g}" for v in values) + "\n")
        self._fh.flush()

    @abc.abstractmethod
    def execute(self, sim) -> None:
        """Sample the current state and write a row."""

    def end(self) -> None:
        self._fh.close()
