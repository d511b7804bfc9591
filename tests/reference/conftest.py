"""A Dask cluster of two worker processes on 127.0.0.1, started by the tests themselves (the engine's own local
start), with a file cache of its own: what a scene ships to it is seen there."""

from __future__ import annotations

import logging

import pytest


@pytest.fixture(scope="session")
def cluster(tmp_path_factory):
    from distributed import LocalCluster

    cache = tmp_path_factory.mktemp("worker-cache")
    local = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                         dashboard_address=None, silence_logs=logging.ERROR,
                         env={"XDG_CACHE_HOME": str(cache)})  # fmt: skip
    local.cache = cache
    yield local
    local.close()
