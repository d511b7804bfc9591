"""Area-light method 'ltc' (being written)."""
