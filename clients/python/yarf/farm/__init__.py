"""A render farm on NATS JetStream: one coordinator, any number of render nodes.

The coordinator (``yarf-farm coordinator``) serves yarf.v1.RenderService like
a yarfd, keeps its job table in SQLite and splits every job into tasks:
sample-pass shares (``RenderOptions.first_sample``) and, for large images,
crop tiles. Render nodes (``yarf-farm node``) render tasks on their own
yarfd; the coordinator merges the images by sample count. What travels
where (names in ``yarf.farm.streams``):

- the scene, once per scene: object store ``yarf-scenes``, key = sha256;
- tasks: work-queue stream ``YARF_TASKS``, subjects
  ``yarf.tasks.<high|normal|low>.<job>``, one durable pull consumer per
  tier shared by every node; ``Nats-Msg-Id`` makes republishing harmless;
- cancel flags and progress: key-value bucket ``yarf-jobs``;
- task images: object store ``yarf-results``, announced on the
  ``YARF_RESULTS`` stream (``yarf.results.<job>``) that the coordinator
  consumes with a durable consumer, acking once the result is in SQLite.

Run ``nats-server -js -sd DIR``, then for example::

    yarf-farm coordinator --nats nats://127.0.0.1:4222 --listen 127.0.0.1:50051 \\
        --state-dir /var/lib/yarf-farm
    yarf-farm node --nats nats://127.0.0.1:4222 --threads 8

and point any yarf client at 127.0.0.1:50051. Beyond loopback the
coordinator requires ``--tls-cert``, ``--tls-key`` and ``--tokens``, as
yarfd does (``yarf.farm.listen``, ``yarf.farm.auth``); each job is its
submitter's (``yarf.farm.access``).
"""
