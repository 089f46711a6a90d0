"""Background loops that end when asked, whatever the NATS client does with a cancel.

nats-py turns a cancellation that meets one of its own timeouts into a
``TimeoutError`` or a closed-connection error now and then (Python 3.11's
``asyncio.wait_for`` may swallow it too). A loop that retries on errors
then never ends, and a process waiting for it never exits. So every loop
also asks ``running`` before each round, and ``stop`` waits a bounded time.
nats-py's own reconnect loop can lose its cancel the same way, so a farm
process runs through ``run``, which cancels what is left again and again
for a bounded time instead of waiting on one cancel as ``asyncio.run`` does.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Coroutine
from typing import Any, TypeVar

log = logging.getLogger(__name__)

STOP_SECONDS = 5.0
# How often ``run`` cancels the tasks still there at the end.
CANCEL_INTERVAL_SECONDS = 0.1

T = TypeVar("T")


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


def run(main: Coroutine[Any, Any, T], timeout: float = STOP_SECONDS) -> T:
    """``asyncio.run(main)``, except that no task left behind keeps the process alive.

    Tasks still running when ``main`` returns are cancelled every
    CANCEL_INTERVAL_SECONDS until they end; after ``timeout`` those that
    never do are named in the log and abandoned with the loop.
    """
    loop = asyncio.new_event_loop()
    asyncio.set_event_loop(loop)
    try:
        return loop.run_until_complete(main)
    finally:
        try:
            loop.run_until_complete(_end_tasks(timeout))
            loop.run_until_complete(loop.shutdown_asyncgens())
            loop.run_until_complete(loop.shutdown_default_executor())
        finally:
            asyncio.set_event_loop(None)
            loop.close()


async def _end_tasks(timeout: float) -> None:
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    while tasks := asyncio.all_tasks() - {asyncio.current_task()}:
        if loop.time() >= deadline:
            names = ", ".join(sorted(task.get_name() for task in tasks))
            log.warning("abandoned tasks that ignored %.0f s of cancels: %s", timeout, names)
            return
        for task in tasks:
            task.cancel()
        await asyncio.wait(tasks, timeout=CANCEL_INTERVAL_SECONDS)
