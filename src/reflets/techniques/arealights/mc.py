"""Area-light method 'mc' (being written)."""
