"""Studies that loop over analyses: the convergence study of rod models."""

__all__: list[str] = []
