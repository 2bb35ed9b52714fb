"""What every feature shares: the compiled core, errors, long jobs, the cache, preferences, scene geometry, panel helpers."""
