"""Pictures: mode shapes and receptances, off-screen (imported only when drawing)."""

__all__: list[str] = []
