"""Area-light method 'biased' (being written)."""
