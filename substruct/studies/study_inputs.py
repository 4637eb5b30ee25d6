"""What a study's parameters must do before any sample runs: reach the model, and not be set
twice.

A study varies ``parameters``; each sample is the case with ``--set parameters.<name>=<value>``
for its values, applied after the command line's overrides.  So a ``--set parameters.kc=...``
of a parameter the study varies would be replaced in every sample without a word, and a varied
parameter that no field of the case names (a misspelt use, or a use that a ``--set`` of the
field replaced by a number) would give the same model in every sample, a table of identical
rows.  Both are refused in one line naming the field and the value.

A parameter is used when an identifier of a string anywhere in the case names it (the
expressions of every field, the points, the other parameters, the study's ``collect``), except
in the free text ``name``, ``description`` and ``units``, and the study's own axes.
"""

from __future__ import annotations

import re

from substruct.case.loader import Case
from substruct.case.yaml_io import load_yaml
from substruct.studies.study_shared import identifiers, varied_parameters

__all__ = ["check_study_parameters"]

#: Top-level keys of free text, whose words are not uses of a parameter.
FREE_TEXT = ("name", "description", "units")


def check_study_parameters(case: Case, names: list[str]) -> None:
    """Refuse a ``--set`` of a parameter the study varies, and a varied parameter that nothing
    of the case (as overridden) uses (module docstring); ``names``: the varied parameters.

    Raises:
        CaseError: at ``parameters.<name>``, naming the value.
    """
    for item in case.overrides:
        parts = [p for p in re.split(r"[.\[\]]", item.partition("=")[0].strip()) if p]
        for name in names:
            if parts == ["parameters", name]:   # parameters.k1 or parameters[k1]
                raise case.error(("parameters", name), "the study varies this parameter: its "
                                 "values replace the one of --set in every sample (leave it "
                                 "out of --set)", item.partition("=")[2].strip())
    raw = load_yaml(case.text, case.source)
    if not isinstance(raw, dict):
        return
    study_raw, params_raw = raw.get("study"), raw.get("parameters")
    study: dict = study_raw if isinstance(study_raw, dict) else {}
    params: dict = params_raw if isinstance(params_raw, dict) else {}
    body = {k: v for k, v in raw.items() if k not in ("parameters", "study", *FREE_TEXT)}
    uses = identifiers([body, study.get("collect")])
    reaching = {str(p) for p in params if str(p) in uses}  # used by the model directly
    for name in names:
        derived = varied_parameters(raw, [name]) - {name}  # the parameters computed from it
        if name not in uses and not (derived & reaching):
            raise case.error(("parameters", name), "the study varies this parameter but no "
                             "field of the case uses it (no expression or point names it): "
                             "every sample would be the same", params.get(name))
