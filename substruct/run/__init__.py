"""Running a case: the analyses it asks for on its model, into one
:class:`~substruct.run.result.Result`."""

from substruct.run.runner import Model, Progress, build_model, run_case

__all__ = ["Model", "Progress", "build_model", "run_case"]
