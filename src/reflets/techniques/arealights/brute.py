"""Area-light method 'brute' (being written)."""
