"""Area-light method 'adaptive' (being written)."""
