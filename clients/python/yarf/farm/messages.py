"""The messages on the farm's streams: tasks (coordinator → nodes) and results (back).

Both are small JSON documents; scenes and images travel in object stores
and are named here.
"""

from __future__ import annotations

import base64
import json
from dataclasses import dataclass

from yarf.farm.tasks import Window
from yarf.v1 import render_pb2


@dataclass(frozen=True)
class TaskMessage:
    """A task for a node: the job's options narrowed to the task, the scene by hash."""

    farm: str
    job_id: str
    task: int
    scene_hash: str
    options: render_pb2.RenderOptions
    window: Window
    name: str

    def encode(self) -> bytes:
        return json.dumps(
            {
                "farm": self.farm,
                "job": self.job_id,
                "task": self.task,
                "scene": self.scene_hash,
                "options": base64.b64encode(self.options.SerializeToString()).decode(),
                "window": [self.window.x0, self.window.y0, self.window.x1, self.window.y1],
                "name": self.name,
            }
        ).encode()

    @classmethod
    def decode(cls, data: bytes) -> TaskMessage:
        fields = json.loads(data)
        return cls(
            farm=str(fields["farm"]),
            job_id=str(fields["job"]),
            task=int(fields["task"]),
            scene_hash=str(fields["scene"]),
            options=render_pb2.RenderOptions.FromString(base64.b64decode(fields["options"])),
            window=Window(*(int(v) for v in fields["window"])),
            name=str(fields.get("name", "")),
        )

    def msg_id(self, generation: int, again: str = "") -> str:
        """The Nats-Msg-Id: publishing a task again within the duplicate window is a no-op.

        ``generation`` changes when the job's tasks move tier; ``again``
        names a deliberate second publication (a retry after a failure).
        """
        base = f"{self.farm}/{self.job_id}/{self.task}/{generation}"
        return f"{base}/{again}" if again else base


@dataclass(frozen=True)
class ResultMessage:
    """A node's report on a task: the image's object name, or why it failed."""

    farm: str
    job_id: str
    task: int
    node: str
    ok: bool
    error: str = ""
    image_object: str = ""
    closest_hit_rays: int = 0
    shadow_rays: int = 0
    render_seconds: float = 0.0

    def encode(self) -> bytes:
        return json.dumps(self.__dict__).encode()

    @classmethod
    def decode(cls, data: bytes) -> ResultMessage:
        return cls(**json.loads(data))

    @staticmethod
    def image_object_name(farm: str, job_id: str, task: int, render: str) -> str:
        """A name per rendering: a task rendered twice never overwrites an image being read."""
        return f"{farm}/{job_id}/{task}/{render}"
