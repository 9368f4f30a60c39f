"""Parts of ``scripts/generate_steam_tables.py``: the forward IF97 states (``if97``) and the
fast-path tables (``fast``)."""
