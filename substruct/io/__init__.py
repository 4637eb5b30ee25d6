"""Results on disk: the HDF5 result file (atomic, written as a set) and exports for
ParaView (VTU, XDMF)."""

__all__: list[str] = []
