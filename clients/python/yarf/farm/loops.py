"""Background loops that end when asked, whatever the NATS client does with a cancel.

nats-py turns a cancellation that meets one of its own timeouts into a
``TimeoutError`` or a closed-connection error now and then (Python 3.11's
``asyncio.wait_for`` may swallow it too). A loop that retries on errors
then never ends, and a process waiting for it never exits. So every loop
also asks ``running`` before each round, and ``stop`` waits a bounded time.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Coroutine
from typing import Any

log = logging.getLogger(__name__)

STOP_SECONDS = 5.0


class Loops:
    """Tasks that run until ``stop``; their coroutines loop ``while loops.running``."""

    def __init__(self) -> None:
        self.running = True
        self._tasks: set[asyncio.Task[None]] = set()

    def start(self, coroutine: Coroutine[Any, Any, None], name: str) -> asyncio.Task[None]:
        task = asyncio.create_task(coroutine, name=name)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)
        return task

    async def stop(self, timeout: float = STOP_SECONDS) -> None:
        """Ends every loop: at its next round, or at once when the cancel gets through."""
        self.running = False
        tasks = list(self._tasks)
        for task in tasks:
            task.cancel()
        if not tasks:
            return
        _, pending = await asyncio.wait(tasks, timeout=timeout)
        for task in pending:
            log.warning("%s did not stop within %.0f s", task.get_name(), timeout)
