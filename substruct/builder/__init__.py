"""From a validated case to an assembled model: substructures made from their
specifications, points resolved, drawings laid out, constraints checked."""

__all__: list[str] = []
