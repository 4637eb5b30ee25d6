"""Case files: YAML loading, the validated schema, safe expressions and one-line errors.

Nothing numerical happens here; the layers below :mod:`substruct.builder` turn a case into
matrices."""

from substruct.case.errors import CaseError
from substruct.case.loader import Case, load_case, parse_case
from substruct.case.yaml_io import apply_overrides
from substruct.case.fields import parse_point

__all__ = ["Case", "CaseError", "apply_overrides", "load_case", "parse_case", "parse_point"]
