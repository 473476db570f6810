"""``pfusion tma-input``: the operator's TMA bounds and support values per track."""
