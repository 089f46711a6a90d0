"""Static checks of deploy/: no container engine or cluster runs here.

- Kubernetes manifests against the Kubernetes JSON schemas
  (kubernetes-validate, offline, strict) and against each other (selectors,
  named ports, volumes, ConfigMap keys, probes, limits, pinned images).
- compose.yaml against the Compose specification schema (the copy
  check-jsonschema ships) and for references the schema cannot see.
- The Dockerfile through BuildKit's parser (the `dockerfile` package):
  pinned bases, a non-root final stage, apt lists cleaned, COPY sources in
  the build context, commands the image really contains, and runtime
  packages that cover every library the built binaries link.
- The systemd units with `systemd-analyze verify` and `security --offline`.
- Every yarfd and yarf-farm flag any deploy file uses, against the usage
  text the built programs print now; and TLS with tokens for every server
  listening beyond loopback whose program offers them.
- The image's health probe (docker/healthcheck.py) against real gRPC
  servers, plaintext and TLS.

Each checker returns a list of problems; the tests after the checks feed
each one a broken input to prove it can fail.
"""

from __future__ import annotations

import fnmatch
import functools
import importlib.resources
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import tomllib
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from typing import Any

import dockerfile
import grpc
import jsonschema
import kubernetes_validate
import pytest
import yaml
from kubernetes_validate.utils import all_versions

REPO = Path(__file__).resolve().parents[1]
DEPLOY = REPO / "deploy"
K8S = DEPLOY / "k8s"
SYSTEMD = DEPLOY / "systemd"
DOCKERFILE = DEPLOY / "docker" / "Dockerfile"
DOCKERIGNORE = DEPLOY / "docker" / "Dockerfile.dockerignore"
COMPOSE = DEPLOY / "compose.yaml"
YARFD = REPO / "build" / "bin" / "yarfd"
VENV_BIN = REPO / ".venv" / "bin"
# The image every yarf process runs from (compose.yaml, k8s/).
YARF_IMAGE = re.compile(r"^yarf(:|$)")
PROGRAMS = ("yarfd", "yarf-farm")
TLS_FLAGS = ("--tls-cert", "--tls-key", "--tokens")
SHELL_SEPARATORS = {"&&", "||", ";", "|"}
K8S_NOT_RESOURCES = {"kustomization.yaml"}


# --- what the deploy files run -------------------------------------------


@dataclass
class Invocation:
    """One command line in a deploy file, with the variables it can resolve."""

    where: str
    argv: list[str]
    env: dict[str, str] = field(default_factory=dict)
    # The container image it runs in, if any.
    image: str = ""


def substitute(text: str, env: dict[str, str]) -> str:
    """$(X) (Kubernetes), ${X}, ${X:-default} and $X, from env; unknown ones stay."""

    def value(match: re.Match[str]) -> str:
        name = match.group("k8s") or match.group("braced") or match.group("bare")
        if name in env:
            return env[name]
        default = match.group("default")
        return default if default is not None else match.group(0)

    pattern = (
        r"\$\((?P<k8s>\w+)\)"
        r"|\$\{(?P<braced>\w+)(?::-(?P<default>[^}]*))?\}"
        r"|\$(?P<bare>[A-Za-z_]\w*)"
    )
    return re.sub(pattern, value, text)


def program_calls(invocation: Invocation) -> Iterator[tuple[str, list[str]]]:
    """(yarfd | yarf-farm, its arguments) for each command of argv that runs one."""
    argv = invocation.argv
    for i, token in enumerate(argv):
        name = PurePosixPath(token).name
        starts_command = i == 0 or argv[i - 1] in SHELL_SEPARATORS | {"sudo", "exec"}
        if name not in PROGRAMS or not starts_command:
            continue
        args: list[str] = []
        for arg in argv[i + 1 :]:
            if arg in SHELL_SEPARATORS:
                break
            args.append(arg)
        yield name, args


def parse_unit(path: Path) -> list[tuple[str, str, str]]:
    """(section, key, value) of a systemd unit file, continuation lines joined."""
    entries: list[tuple[str, str, str]] = []
    section = ""
    pending = ""
    for raw in path.read_text().splitlines():
        line = raw.strip()
        if not pending and (not line or line[0] in "#;"):
            continue
        if line.endswith("\\"):
            pending += line[:-1] + " "
            continue
        line, pending = pending + line, ""
        if line.startswith("["):
            section = line.strip("[]")
        elif "=" in line:
            key, value = line.split("=", 1)
            entries.append((section, key.strip(), value.strip()))
    return entries


def unit_environment(entries: list[tuple[str, str, str]]) -> dict[str, str]:
    env: dict[str, str] = {}
    for _, key, value in entries:
        if key == "Environment":
            for assignment in shlex.split(value):
                name, _, setting = assignment.partition("=")
                env[name] = setting
    return env


def unit_invocations(path: Path) -> list[Invocation]:
    entries = parse_unit(path)
    env = unit_environment(entries)
    calls = []
    for _, key, value in entries:
        if key.startswith("Exec") and value:
            calls.append(Invocation(f"{path.name} {key}", shlex.split(value.lstrip("-@:+!")), env))
    return calls


def command_list(value: str | list[str] | None) -> list[str]:
    if value is None:
        return []
    return shlex.split(value) if isinstance(value, str) else [str(v) for v in value]


def compose_invocations(compose: dict[str, Any]) -> list[Invocation]:
    calls = []
    for name, service in compose.get("services", {}).items():
        image = service.get("image", "")
        argv = command_list(service.get("entrypoint")) + command_list(service.get("command"))
        if argv:
            calls.append(Invocation(f"compose.yaml services.{name}", argv, image=image))
        test = command_list(service.get("healthcheck", {}).get("test"))
        if test and test[0] in ("CMD", "CMD-SHELL"):
            argv = test[1:] if test[0] == "CMD" else shlex.split(" ".join(test[1:]))
            where = f"compose.yaml services.{name}.healthcheck"
            calls.append(Invocation(where, argv, image=image))
    return calls


def pod_spec(resource: dict[str, Any]) -> dict[str, Any] | None:
    if resource.get("kind") in ("Deployment", "StatefulSet", "DaemonSet", "Job"):
        return resource["spec"]["template"]["spec"]
    return resource["spec"] if resource.get("kind") == "Pod" else None


def containers(spec: dict[str, Any]) -> list[dict[str, Any]]:
    return list(spec.get("initContainers", [])) + list(spec.get("containers", []))


def k8s_invocations(path: Path, resource: dict[str, Any]) -> list[Invocation]:
    spec = pod_spec(resource)
    if spec is None:
        return []
    calls = []
    for container in containers(spec):
        where = f"{path.name} {resource['metadata']['name']}/{container['name']}"
        env = {e["name"]: str(e["value"]) for e in container.get("env", []) if "value" in e}
        image = container["image"]
        argv = command_list(container.get("command")) + command_list(container.get("args"))
        if argv:
            calls.append(Invocation(where, argv, env, image))
        for probe in ("readinessProbe", "livenessProbe", "startupProbe"):
            command = container.get(probe, {}).get("exec", {}).get("command")
            if command:
                calls.append(Invocation(f"{where} {probe}", command_list(command), env, image))
    return calls


def dockerfile_invocations(commands: list[Any]) -> list[Invocation]:
    calls = []
    for command in commands:
        if command.cmd not in ("CMD", "ENTRYPOINT", "HEALTHCHECK"):
            continue
        value = list(command.value)
        if command.cmd == "HEALTHCHECK":
            if value[:1] != ["CMD"]:
                continue
            value = value[1:]
        argv = value if command.json else shlex.split(" ".join(value))
        calls.append(Invocation(f"Dockerfile:{command.start_line} {command.cmd}", argv))
    return calls


def readme_invocations(path: Path) -> list[Invocation]:
    """Command lines of the fenced shell blocks of a Markdown file."""
    calls = []
    in_block = False
    pending = ""
    for number, raw in enumerate(path.read_text().splitlines(), 1):
        if raw.startswith("```"):
            in_block = not in_block
            continue
        if not in_block:
            continue
        line = pending + raw.strip()
        if line.endswith("\\"):
            pending = line[:-1] + " "
            continue
        pending = ""
        if line and not line.startswith("#"):
            calls.append(Invocation(f"{path.name}:{number}", shlex.split(line, comments=True)))
    return calls


def yaml_documents(path: Path) -> list[dict[str, Any]]:
    return [doc for doc in yaml.safe_load_all(path.read_text()) if doc]


def k8s_files() -> list[Path]:
    return sorted(p for p in K8S.glob("*.yaml") if p.name not in K8S_NOT_RESOURCES)


def k8s_resources() -> list[tuple[Path, dict[str, Any]]]:
    return [(path, doc) for path in k8s_files() for doc in yaml_documents(path)]


def all_invocations() -> list[Invocation]:
    calls = dockerfile_invocations(dockerfile.parse_file(str(DOCKERFILE)))
    calls += compose_invocations(yaml.safe_load(COMPOSE.read_text()))
    for path, resource in k8s_resources():
        calls += k8s_invocations(path, resource)
    for unit in sorted(SYSTEMD.rglob("*.service")):
        calls += unit_invocations(unit)
    calls += readme_invocations(DEPLOY / "README.md")
    return calls


# --- the flags the programs accept, from their own usage text ------------


def usage_flags(text: str) -> set[str]:
    return set(re.findall(r"(?<![\w-])--[a-z0-9][a-z0-9-]*", text))


@functools.cache
def yarfd_usage() -> str:
    """yarfd's usage text: it prints it and exits non-zero on --help."""
    run = subprocess.run(
        [str(YARFD), "--help"], capture_output=True, text=True, timeout=30, check=False
    )
    text = run.stdout + run.stderr
    if "usage: yarfd" not in text:
        pytest.fail(f"{YARFD} --help printed no usage (exit status {run.returncode}):\n{text}")
    return text


def yarf_farm() -> Path | None:
    found = VENV_BIN / "yarf-farm"
    if found.exists():
        return found
    on_path = shutil.which("yarf-farm")
    return Path(on_path) if on_path else None


@functools.cache
def yarf_farm_usage(subcommand: str) -> str | None:
    """`yarf-farm SUBCOMMAND --help`; None when there is no such subcommand."""
    program = yarf_farm()
    assert program is not None
    run = subprocess.run(
        [str(program), subcommand, "--help"],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    return run.stdout if run.returncode == 0 else None


class UnknownCommand(Exception):
    pass


def usage_of(program: str, args: list[str]) -> tuple[set[str], list[str]] | None:
    """The flags `program` accepts (for yarf-farm, its subcommand's) and the
    arguments they apply to; None when yarf-farm is not installed."""
    if program == "yarfd":
        return usage_flags(yarfd_usage()), args
    if yarf_farm() is None:
        return None
    subcommand = next((a for a in args if not a.startswith("-")), "")
    usage = yarf_farm_usage(subcommand) if subcommand else None
    if usage is None:
        raise UnknownCommand(f"yarf-farm has no subcommand {subcommand!r}")
    return usage_flags(usage), args[args.index(subcommand) + 1 :]


def flag_problems(calls: list[Invocation]) -> list[str]:
    problems = []
    for call in calls:
        for program, args in program_calls(call):
            try:
                usage = usage_of(program, args)
            except UnknownCommand as error:
                problems.append(f"{call.where}: {error}")
                continue
            if usage is None:
                continue  # test_deploy_flags_are_accepted_by_the_programs says so
            accepted, used = usage
            for arg in used:
                flag = arg.split("=", 1)[0]
                if flag.startswith("--") and flag not in accepted:
                    problems.append(f"{call.where}: {program} does not accept {flag}")
    return problems


def is_loopback(address: str) -> bool:
    host = address.rsplit(":", 1)[0].strip("[]")
    return address.startswith("unix:") or host in ("localhost", "::1") or host.startswith("127.")


def tls_problems(calls: list[Invocation]) -> tuple[list[str], list[str]]:
    """A server listening beyond loopback must be given TLS and tokens.

    Returns the problems, and the servers that listen beyond loopback in
    plaintext because their program has no TLS options to give.
    """
    problems = []
    plaintext = []
    for call in calls:
        for program, args in program_calls(call):
            if "--listen" not in args or args.index("--listen") + 1 >= len(args):
                continue
            address = substitute(args[args.index("--listen") + 1], call.env)
            missing = [f for f in TLS_FLAGS if f not in args]
            if is_loopback(address) or not missing:
                continue
            usage = usage_of(program, args)
            if usage is not None and not set(TLS_FLAGS) <= usage[0]:
                plaintext.append(f"{call.where} ({address})")
            else:
                problems.append(f"{call.where}: {program} on {address} without {missing}")
    return problems, plaintext


# --- Kubernetes ----------------------------------------------------------


def k8s_schema_problems(path: Path, resource: dict[str, Any]) -> list[str]:
    """Strict schema validation at the oldest and newest Kubernetes bundled."""
    versions = all_versions()
    problems = []
    for version in sorted({versions[0], versions[-1]}):
        try:
            kubernetes_validate.validate(resource, version, strict=True)
        except kubernetes_validate.ValidationError as error:
            where = "/".join(str(p) for p in error.path)
            problems.append(f"{path.name} {resource.get('kind')} {where}: {error.message}")
        except kubernetes_validate.SchemaNotFoundError as error:
            problems.append(f"{path.name}: {error.message}")
    return problems


def image_problems(where: str, image: str) -> list[str]:
    name = image.split("@", 1)[0]
    tag = name.rsplit(":", 1)[1] if ":" in name.rsplit("/", 1)[-1] else ""
    if "@sha256:" in image:
        return []
    if not tag:
        return [f"{where}: image {image} has no tag"]
    return [f"{where}: image {image} is not pinned"] if tag == "latest" else []


def k8s_reference_problems(resources: list[tuple[Path, dict[str, Any]]]) -> list[str]:
    """What the schemas cannot see: names that must agree across objects."""
    problems: list[str] = []
    namespaces = {r["metadata"]["name"] for _, r in resources if r["kind"] == "Namespace"}
    config_maps = {
        r["metadata"]["name"]: set(r.get("data", {}))
        for _, r in resources
        if r["kind"] == "ConfigMap"
    }
    pods: list[tuple[dict[str, str], dict[str, Any]]] = []
    for path, resource in resources:
        where = f"{path.name} {resource['kind']}/{resource['metadata']['name']}"
        namespace = resource["metadata"].get("namespace")
        if resource["kind"] != "Namespace" and namespace not in namespaces:
            problems.append(f"{where}: namespace {namespace!r} is not defined here")
        spec = pod_spec(resource)
        if spec is None:
            continue
        labels = resource["spec"]["template"]["metadata"].get("labels", {})
        selector = resource["spec"].get("selector", {}).get("matchLabels", {})
        if not selector.items() <= labels.items():
            problems.append(f"{where}: selector {selector} does not match its pods {labels}")
        pods.append((labels, spec))
        volumes = {v["name"]: v for v in spec.get("volumes", [])}
        claims = {c["metadata"]["name"] for c in resource["spec"].get("volumeClaimTemplates", [])}
        for container in containers(spec):
            image = container["image"]
            problems += image_problems(where, image)
            for mount in container.get("volumeMounts", []):
                if mount["name"] not in volumes and mount["name"] not in claims:
                    problems.append(f"{where}: volume {mount['name']} is not declared")
            for env in container.get("env", []):
                ref = env.get("valueFrom", {}).get("configMapKeyRef")
                if ref and ref["key"] not in config_maps.get(ref["name"], set()):
                    problems.append(f"{where}: ConfigMap {ref['name']} has no {ref['key']}")
            if container.get("ports") and not (
                container.get("readinessProbe") and container.get("livenessProbe")
            ):
                problems.append(f"{where}: {container['name']} serves ports without probes")
            if "limits" not in container.get("resources", {}):
                problems.append(f"{where}: {container['name']} has no resource limits")
    for path, resource in resources:
        if resource["kind"] != "Service":
            continue
        where = f"{path.name} Service/{resource['metadata']['name']}"
        selector = resource["spec"].get("selector", {})
        matched = [spec for labels, spec in pods if selector.items() <= labels.items()]
        if not matched:
            problems.append(f"{where}: selects no pod {selector}")
            continue
        port_names = {
            port.get("name") for spec in matched for c in containers(spec) for port in c["ports"]
        }
        for port in resource["spec"]["ports"]:
            target = port.get("targetPort")
            if isinstance(target, str) and target not in port_names:
                problems.append(f"{where}: targetPort {target} is no container port")
    return problems


# --- compose -------------------------------------------------------------


@functools.cache
def compose_schema() -> dict[str, Any]:
    schema = importlib.resources.files("check_jsonschema").joinpath(
        "builtin_schemas/vendor/compose-spec.json"
    )
    return json.loads(schema.read_text())


def compose_schema_problems(compose: dict[str, Any]) -> list[str]:
    validator = jsonschema.Draft202012Validator(compose_schema())
    return [f"compose.yaml {e.json_path}: {e.message}" for e in validator.iter_errors(compose)]


def compose_reference_problems(compose: dict[str, Any], base: Path) -> list[str]:
    problems: list[str] = []
    services = compose.get("services", {})
    volumes = set(compose.get("volumes") or {})
    secrets = compose.get("secrets") or {}
    for name, service in services.items():
        where = f"compose.yaml services.{name}"
        if "image" in service:
            problems += image_problems(where, service["image"])
        build = service.get("build")
        if isinstance(build, dict):
            context = base / build.get("context", ".")
            if not (context / build.get("dockerfile", "Dockerfile")).is_file():
                problems.append(f"{where}: build file {build} not found")
        for volume in service.get("volumes", []):
            source = volume.split(":", 1)[0] if isinstance(volume, str) else volume.get("source")
            if source and not source.startswith((".", "/", "$")) and source not in volumes:
                problems.append(f"{where}: volume {source} is not declared")
        for secret in service.get("secrets", []):
            source = secret if isinstance(secret, str) else secret["source"]
            if source not in secrets:
                problems.append(f"{where}: secret {source} is not declared")
        for dependency in service.get("depends_on", {}):
            if dependency not in services:
                problems.append(f"{where}: depends on unknown service {dependency}")
        if "healthcheck" not in service:
            problems.append(f"{where}: no healthcheck (or an explicit `disable: true`)")
    return problems


# --- Dockerfile ----------------------------------------------------------


@dataclass
class Stage:
    name: str
    base: str
    commands: list[Any]


def dockerfile_stages(commands: list[Any]) -> list[Stage]:
    args: dict[str, str] = {}
    stages: list[Stage] = []
    for command in commands:
        if command.cmd == "ARG" and not stages:
            name, _, default = command.value[0].partition("=")
            args[name] = default
        elif command.cmd == "FROM":
            value = list(command.value)
            name = value[2] if len(value) >= 3 and value[1].upper() == "AS" else str(len(stages))
            stages.append(Stage(name, substitute(value[0], args), []))
        elif stages:
            stages[-1].commands.append(command)
    return stages


def ignored(path: str, patterns: list[str]) -> bool:
    """Whether .dockerignore patterns (last match wins, ! re-includes) drop path."""
    parts = PurePosixPath(path).parts
    prefixes = ["/".join(parts[: i + 1]) for i in range(len(parts))]
    result = False
    for pattern in patterns:
        negate = pattern.startswith("!")
        glob = pattern.lstrip("!").strip("/")
        globs = [glob, glob.replace("**/", "")] if glob.startswith("**/") else [glob]
        if any(fnmatch.fnmatchcase(p, g) for p in prefixes for g in globs):
            result = not negate
    return result


def cmake_executables() -> set[str]:
    """Executables the CMake build makes (the folders the top CMakeLists.txt adds)."""
    top = (REPO / "CMakeLists.txt").read_text()
    names = set()
    for folder in re.findall(r"add_subdirectory\(\s*([\w/.-]+)", top):
        for lists in (REPO / folder).rglob("CMakeLists.txt"):
            names.update(re.findall(r"add_executable\(\s*([\w.-]+)", lists.read_text()))
    return names


def console_scripts() -> set[str]:
    project = tomllib.loads((REPO / "clients" / "python" / "pyproject.toml").read_text())
    return set(project["project"].get("scripts", {}))


def image_programs(stages: list[Stage]) -> dict[str, str]:
    """Program name → where the final stage gets it, for names on its PATH."""
    final = stages[-1]
    path = ["/usr/local/bin", "/usr/bin", "/bin"]
    for command in final.commands:
        if command.cmd == "ENV":
            pairs = dict(zip(command.value[::2], command.value[1::2], strict=True))
            if "PATH" in pairs:
                path = pairs["PATH"].replace("$PATH", ":".join(path)).split(":")
    programs: dict[str, str] = {}
    for command in final.commands:
        if command.cmd != "COPY" or "--from=" not in " ".join(command.flags):
            continue
        *sources, dest = command.value
        for source in sources:
            if source.rstrip("/").endswith("/venv") and f"{dest.rstrip('/')}/bin" in path:
                # A venv: its interpreter and the client's console scripts.
                for script in [*console_scripts(), "python", "python3"]:
                    programs[script] = f"venv {source}"
            elif dest.rstrip("/") in path:
                programs[PurePosixPath(source).name] = source
    for command in final.commands:
        if command.cmd == "RUN" and re.search(r"apt-get install[^&]*\bpython3\b", command.value[0]):
            programs.setdefault("python3", "apt python3")
    return programs


def image_files(stages: list[Stage]) -> set[str]:
    """Files the final stage COPYs in by name (destination paths)."""
    files = set()
    for command in stages[-1].commands:
        if command.cmd == "COPY":
            *sources, dest = command.value
            for source in sources:
                files.add(dest + PurePosixPath(source).name if dest.endswith("/") else dest)
    return files


def command_problems(stages: list[Stage], calls: list[Invocation]) -> list[str]:
    """Each command the image runs is a program it contains, built as it should be."""
    programs = image_programs(stages)
    executables = cmake_executables()
    files = image_files(stages)
    problems = []
    for call in calls:
        program = call.argv[0]
        origin = programs.get(program)
        if origin is None:
            problems.append(f"{call.where}: the image has no {program} on its PATH")
        elif origin.startswith("/src/build/bin/") and program not in executables:
            problems.append(f"{call.where}: {program} is no CMake executable")
        for arg in call.argv[1:]:
            if arg.startswith("/usr/local/lib/yarf/") and arg not in files:
                problems.append(f"{call.where}: {arg} is not copied into the image")
    return problems


def dockerfile_problems(commands: list[Any], ignore_patterns: list[str]) -> list[str]:
    problems: list[str] = []
    stages = dockerfile_stages(commands)
    names = [stage.name for stage in stages]
    for index, stage in enumerate(stages):
        base = stage.base
        if base not in names[:index]:
            problems += image_problems(f"Dockerfile stage {stage.name}", base)
        for command in stage.commands:
            where = f"Dockerfile:{command.start_line}"
            text = " ".join(command.value)
            if command.cmd == "RUN" and "apt-get install" in text:
                for needed in ("apt-get update", "--no-install-recommends", "/var/lib/apt/lists"):
                    if needed not in text:
                        problems.append(f"{where}: apt-get install without {needed}")
            if command.cmd in ("COPY", "ADD"):
                origin = next((f for f in command.flags if f.startswith("--from=")), None)
                if origin:
                    if origin.split("=", 1)[1] not in names[:index]:
                        problems.append(f"{where}: {origin} names no earlier stage")
                    continue
                for source in command.value[:-1]:
                    if not list(REPO.glob(source.rstrip("/"))):
                        problems.append(f"{where}: {source} does not exist in the repository")
                    elif ignored(source.rstrip("/"), ignore_patterns):
                        problems.append(f"{where}: {source} is excluded by the .dockerignore")
    users = [c for c in stages[-1].commands if c.cmd == "USER"] if stages else []
    if not users or users[-1].value[0].split(":")[0] in ("root", "0"):
        problems.append("Dockerfile: the final stage does not switch to a non-root USER")
    return problems


def dockerignore_patterns() -> list[str]:
    lines = DOCKERIGNORE.read_text().splitlines()
    return [line.strip() for line in lines if line.strip() and not line.startswith("#")]


def apt_packages(run: str) -> set[str]:
    """The packages of the `apt-get install` in a RUN line."""
    match = re.search(r"apt-get install (.*?)(&&|$)", run)
    words = match.group(1).split() if match else []
    return {w for w in words if not w.startswith("-")}


def runtime_library_problems(stages: list[Stage]) -> list[str]:
    """Every shared library the built binaries link comes with the final stage's packages."""
    if not shutil.which("apt-cache") or not shutil.which("dpkg"):
        pytest.skip("no apt-cache or dpkg: cannot map libraries to Debian packages")
    binaries = [YARFD, REPO / "build" / "bin" / "yarf-import"]
    binaries += sorted((REPO / "build" / "plugins").glob("*.so"))
    listed: set[str] = set()
    for command in stages[-1].commands:
        if command.cmd == "RUN":
            listed |= apt_packages(command.value[0])
    only_depends = ["--no-recommends", "--no-suggests", "--no-conflicts", "--no-breaks"]
    only_depends += ["--no-replaces", "--no-enhances"]
    closure = subprocess.run(
        ["apt-cache", "depends", "--recurse", *only_depends, *sorted(listed)],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    installed = {line.strip() for line in closure.splitlines() if not line.startswith(" ")}
    problems: list[str] = []
    # The libraries they name (DT_NEEDED); the packages of those bring the rest.
    needed: set[str] = set()
    for binary in binaries:
        dynamic = subprocess.run(
            ["objdump", "-p", str(binary)], capture_output=True, text=True, check=True
        ).stdout
        needed.update(re.findall(r"NEEDED\s+(\S+)", dynamic))
    ldd = subprocess.run(
        ["ldd", *map(str, binaries)], capture_output=True, text=True, check=True
    ).stdout
    found = dict(re.findall(r"^\s*(\S+) => (/\S+)", ldd, re.MULTILINE))
    # dpkg knows a file by the path its package ships, /lib or /usr/lib.
    candidates: dict[str, str] = {}
    for name in needed - {"ld-linux-x86-64.so.2"}:
        if name not in found:
            problems.append(f"{name}: not found on this machine")
            continue
        for path in {found[name], os.path.realpath(found[name])}:
            for variant in (path, path.removeprefix("/usr"), "/usr" + path):
                candidates[variant] = name
    owners = subprocess.run(
        ["dpkg", "-S", *sorted(candidates)], capture_output=True, text=True, check=False
    ).stdout
    packages: dict[str, str] = {}
    for line in owners.splitlines():
        package, _, path = line.partition(": ")
        if path in candidates:
            packages[candidates[path]] = package.split(",")[0].split(":")[0]
    for name in sorted(needed - {"ld-linux-x86-64.so.2"}):
        if name in found and name not in packages:
            problems.append(f"{name} ({found[name]}): no Debian package provides it")
        elif name in packages and packages[name] not in installed:
            problems.append(f"{name} ({packages[name]}) is not installed by the runtime stage")
    return problems


# --- systemd -------------------------------------------------------------

HARDENING = {
    "NoNewPrivileges": "yes",
    "ProtectSystem": "strict",
    "ProtectHome": "yes",
    "PrivateTmp": "yes",
    "Restart": "on-failure",
}


def unit_rule_problems(path: Path) -> list[str]:
    entries = parse_unit(path)
    settings = {(section, key): value for section, key, value in entries}
    problems = []
    for key, wanted in HARDENING.items():
        if settings.get(("Service", key)) != wanted:
            problems.append(f"{path.name}: {key}={wanted} is missing")
    if settings.get(("Service", "User"), "root") in ("root", "0"):
        problems.append(f"{path.name}: no dedicated User=")
    if ("Service", "StateDirectory") not in settings:
        problems.append(f"{path.name}: no StateDirectory=")
    for call in unit_invocations(path):
        if not call.argv[0].startswith("/usr/local/bin/"):
            problems.append(f"{call.where}: {call.argv[0]} is not in /usr/local/bin")
    return problems


def unit_copies(units: list[Path], folder: Path) -> list[Path]:
    """Copies whose ExecStart runs programs that exist here.

    systemd-analyze verify fails on a missing ExecStart binary, and the
    units name their installed paths: yarfd becomes the built one, yarf-farm
    the venv's (or /usr/bin/true before the farm is installed; its flags
    are checked against its usage text separately).
    """
    farm = yarf_farm()
    replacements = {
        "/usr/local/bin/yarfd": str(YARFD),
        "/usr/local/bin/yarf-farm": str(farm) if farm else "/usr/bin/true",
    }
    copies = []
    for unit in units:
        text = unit.read_text()
        for installed, here in replacements.items():
            text = text.replace(installed, here)
        copy = folder / unit.relative_to(SYSTEMD)
        copy.parent.mkdir(parents=True, exist_ok=True)
        copy.write_text(text)
        copies.append(copy)
    return copies


def systemd_verify_problems(units: list[Path], folder: Path) -> list[str]:
    """systemd-analyze verify: exit status and every complaint about these files."""
    env = {**os.environ, "SYSTEMD_UNIT_PATH": f"{folder}:"}
    run = subprocess.run(
        ["systemd-analyze", "verify", *map(str, units)],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
        check=False,
    )
    output = run.stdout + run.stderr
    # Complaints name the file by its path, or the unit by its name.
    names = tuple(f"{unit.name}:" for unit in units)
    ours = [line for line in output.splitlines() if str(folder) in line or line.startswith(names)]
    if run.returncode != 0 or ours:
        return [f"systemd-analyze verify (exit {run.returncode}):\n{output}"]
    return []


def requires_systemd_analyze() -> None:
    if not shutil.which("systemd-analyze"):
        pytest.skip("systemd-analyze is not installed: the units are unverified")


def requires_yarfd() -> None:
    assert YARFD.exists(), f"{YARFD} is not built (make build)"


# --- the tests -----------------------------------------------------------


@pytest.mark.parametrize("path", k8s_files(), ids=lambda p: p.name)
def test_k8s_manifests_match_the_kubernetes_schemas(path: Path) -> None:
    problems = [p for doc in yaml_documents(path) for p in k8s_schema_problems(path, doc)]
    assert problems == []


def test_k8s_manifests_agree_with_each_other() -> None:
    assert k8s_reference_problems(k8s_resources()) == []


def test_kustomization_applies_every_manifest() -> None:
    kustomization = yaml.safe_load((K8S / "kustomization.yaml").read_text())
    assert set(kustomization["resources"]) == {p.name for p in k8s_files()}


def test_compose_file_matches_the_compose_specification() -> None:
    assert compose_schema_problems(yaml.safe_load(COMPOSE.read_text())) == []


def test_compose_file_references_what_it_declares() -> None:
    assert compose_reference_problems(yaml.safe_load(COMPOSE.read_text()), COMPOSE.parent) == []


def test_dockerfile_follows_the_image_rules() -> None:
    commands = list(dockerfile.parse_file(str(DOCKERFILE)))
    assert dockerfile_problems(commands, dockerignore_patterns()) == []


def yarf_image_calls() -> list[Invocation]:
    """Commands run in the yarf image: its own, compose's and the cluster's."""
    calls = dockerfile_invocations(list(dockerfile.parse_file(str(DOCKERFILE))))
    others = compose_invocations(yaml.safe_load(COMPOSE.read_text()))
    for path, resource in k8s_resources():
        others += k8s_invocations(path, resource)
    return calls + [call for call in others if YARF_IMAGE.match(call.image)]


def test_yarf_image_contains_every_program_it_is_asked_to_run() -> None:
    stages = dockerfile_stages(list(dockerfile.parse_file(str(DOCKERFILE))))
    calls = yarf_image_calls()
    assert "yarf-farm" in console_scripts()
    assert calls
    assert command_problems(stages, calls) == []


def test_runtime_stage_installs_every_library_the_binaries_link() -> None:
    requires_yarfd()
    stages = dockerfile_stages(list(dockerfile.parse_file(str(DOCKERFILE))))
    assert runtime_library_problems(stages) == []


@pytest.mark.parametrize("path", sorted(SYSTEMD.glob("*.service")), ids=lambda p: p.name)
def test_systemd_unit_is_hardened_and_runs_installed_programs(path: Path) -> None:
    assert unit_rule_problems(path) == []


def sysusers_problems(config: Path, root: Path) -> list[str]:
    """systemd-sysusers --dry-run on a scratch root: the file parses, users it makes."""
    run = subprocess.run(
        ["systemd-sysusers", f"--root={root}", "--dry-run", str(config.resolve())],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    if run.returncode != 0 or "Creating user" not in run.stderr + run.stdout:
        return [f"systemd-sysusers (exit {run.returncode}):\n{run.stdout}{run.stderr}"]
    return []


def test_sysusers_file_creates_the_units_user(tmp_path: Path) -> None:
    if not shutil.which("systemd-sysusers"):
        pytest.skip("systemd-sysusers is not installed: yarf.sysusers.conf is unverified")
    config = SYSTEMD / "yarf.sysusers.conf"
    assert sysusers_problems(config, tmp_path) == []
    made = {line.split()[1] for line in config.read_text().splitlines() if line.startswith("u ")}
    users = {v for u in SYSTEMD.glob("*.service") for _, k, v in parse_unit(u) if k == "User"}
    assert users <= made
    broken = tmp_path / "broken.conf"
    broken.write_text(config.read_text().replace("u yarf", "u yarf - - - - junk"))
    assert sysusers_problems(broken, tmp_path)


def test_farm_units_start_after_nats() -> None:
    for name in ("yarf-farm-coordinator.service", "yarf-farm-node.service"):
        after = [v for _, k, v in parse_unit(SYSTEMD / name) if k == "After"]
        assert any("nats-server.service" in v.split() for v in after), name
    wants = [v for _, k, v in parse_unit(SYSTEMD / "yarf-farm-coordinator.service") if k == "Wants"]
    assert any("nats-server.service" in v.split() for v in wants)


def test_systemd_units_pass_systemd_analyze_verify(tmp_path: Path) -> None:
    requires_systemd_analyze()
    requires_yarfd()
    units = sorted(SYSTEMD.glob("*.service"))
    assert systemd_verify_problems(unit_copies(units, tmp_path), tmp_path) == []


def test_nats_jetstream_drop_in_passes_systemd_analyze_verify(tmp_path: Path) -> None:
    requires_systemd_analyze()
    debian_unit = Path("/lib/systemd/system/nats-server.service")
    if not debian_unit.exists():
        pytest.skip("Debian's nats-server is not installed: its drop-in is unverified")
    shutil.copy(debian_unit, tmp_path / debian_unit.name)
    drop_ins = sorted((SYSTEMD / "nats-server.service.d").glob("*.conf"))
    unit_copies(drop_ins, tmp_path)
    assert systemd_verify_problems([tmp_path / debian_unit.name], tmp_path) == []
    settings = [(k, v) for p in drop_ins for _, k, v in parse_unit(p)]
    assert any(k == "ExecStart" and "-js" in v.split() for k, v in settings)


@pytest.mark.parametrize("path", sorted(SYSTEMD.glob("*.service")), ids=lambda p: p.name)
def test_systemd_unit_exposure_is_low(path: Path, tmp_path: Path) -> None:
    """systemd's own score of the sandbox: 2.0 or less is its 'OK' band."""
    requires_systemd_analyze()
    requires_yarfd()
    [copy] = unit_copies([path], tmp_path)
    run = subprocess.run(
        ["systemd-analyze", "security", "--offline=yes", "--threshold=20", str(copy)],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr


def test_deploy_flags_are_accepted_by_the_programs() -> None:
    requires_yarfd()
    calls = all_invocations()
    assert {name for call in calls for name, _ in program_calls(call)} == set(PROGRAMS)
    assert yarf_farm() is not None, "yarf-farm is not installed (make venv)"
    assert flag_problems(calls) == []


def test_servers_beyond_loopback_get_tls_and_tokens() -> None:
    requires_yarfd()
    problems, plaintext = tls_problems(all_invocations())
    assert problems == []
    assert plaintext == []


# --- each checker fails on a broken input --------------------------------


def test_k8s_check_rejects_a_misspelt_field() -> None:
    path, resource = next((p, r) for p, r in k8s_resources() if r["kind"] == "Deployment")
    resource["spec"]["replica"] = resource["spec"].pop("replicas")
    assert k8s_schema_problems(path, resource)


def test_k8s_check_rejects_a_service_without_its_port() -> None:
    resources = k8s_resources()
    service = next(r for _, r in resources if r["kind"] == "Service")
    service["spec"]["ports"][0]["targetPort"] = "no-such-port"
    assert any("no-such-port" in p for p in k8s_reference_problems(resources))


def test_compose_check_rejects_an_unknown_key_and_undeclared_names() -> None:
    compose = yaml.safe_load(COMPOSE.read_text())
    compose["services"]["node"]["replica"] = 2
    assert compose_schema_problems(compose)
    compose["services"]["node"]["secrets"] = ["tokens"]
    compose["services"]["node"]["volumes"] = ["no-such-volume:/data"]
    assert len(compose_reference_problems(compose, COMPOSE.parent)) == 2


def test_dockerfile_check_rejects_latest_root_and_missing_sources() -> None:
    broken = (
        "FROM debian:latest AS build\n"
        "RUN apt-get update && apt-get install -y g++\n"
        "COPY no-such-folder /src\n"
        "FROM build\n"
        "USER root\n"
    )
    problems = dockerfile_problems(list(dockerfile.parse_string(broken)), [])
    assert len(problems) == 5, problems


def test_image_command_check_rejects_a_program_the_image_lacks() -> None:
    stages = dockerfile_stages(list(dockerfile.parse_file(str(DOCKERFILE))))
    calls = [Invocation("here", ["yarfd-typo", "--listen", "x"])]
    assert command_problems(stages, calls)


def test_systemd_check_rejects_an_unknown_setting(tmp_path: Path) -> None:
    requires_systemd_analyze()
    requires_yarfd()
    [copy] = unit_copies([SYSTEMD / "yarfd.service"], tmp_path)
    copy.write_text(copy.read_text().replace("PrivateTmp=yes", "PrivateTemp=yes"))
    assert systemd_verify_problems([copy], tmp_path)
    assert unit_rule_problems(copy)


def test_flag_check_rejects_an_option_yarfd_does_not_know() -> None:
    requires_yarfd()
    calls = [Invocation("here", ["/usr/local/bin/yarfd", "--listen", "x", "--no-such-option"])]
    assert flag_problems(calls) == ["here: yarfd does not accept --no-such-option"]


def test_tls_check_rejects_a_public_server_without_tokens() -> None:
    requires_yarfd()
    calls = [
        Invocation("public", ["yarfd", "--listen", "${L}", "--tls-cert", "c"], {"L": "0.0.0.0:1"}),
        Invocation("local", ["yarfd", "--listen", "127.0.0.1:50051"]),
    ]
    problems, plaintext = tls_problems(calls)
    assert [p.split(":")[0] for p in problems] == ["public"]
    assert plaintext == []


# --- the image's health probe --------------------------------------------


def health_server(
    serving: bool, credentials: grpc.ServerCredentials | None = None
) -> tuple[grpc.Server, int]:
    """A gRPC server on loopback, with grpc.health.v1 answering SERVING or without it."""
    server = grpc.server(ThreadPoolExecutor(max_workers=2))
    if serving:
        check = grpc.unary_unary_rpc_method_handler(lambda request, context: b"\x08\x01")
        handler = grpc.method_handlers_generic_handler("grpc.health.v1.Health", {"Check": check})
        server.add_generic_rpc_handlers((handler,))
    if credentials is None:
        port = server.add_insecure_port("127.0.0.1:0")
    else:
        port = server.add_secure_port("127.0.0.1:0", credentials)
    server.start()
    return server, port


def run_probe(address: str, ca: str = "") -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "YARF_HEALTH_ADDRESS": address, "YARF_HEALTH_CA": ca}
    env["YARF_HEALTH_TIMEOUT"] = "5"
    return subprocess.run(
        [sys.executable, str(DEPLOY / "docker" / "healthcheck.py")],
        capture_output=True,
        text=True,
        env=env,
        timeout=60,
        check=False,
    )


def test_health_probe_passes_a_serving_server_and_fails_a_missing_one() -> None:
    server, port = health_server(serving=True)
    try:
        assert run_probe(f"127.0.0.1:{port}").returncode == 0
    finally:
        server.stop(None)
    assert run_probe(f"127.0.0.1:{port}").returncode == 1


def test_health_probe_counts_a_server_without_the_health_service_as_up() -> None:
    server, port = health_server(serving=False)
    try:
        probe = run_probe(f"127.0.0.1:{port}")
    finally:
        server.stop(None)
    assert probe.returncode == 0, probe.stderr
    assert "UNIMPLEMENTED" in probe.stdout


def test_health_probe_speaks_tls(tmp_path: Path) -> None:
    if not shutil.which("openssl"):
        pytest.skip("openssl is not installed: no certificate to test TLS with")
    key, cert = tmp_path / "tls.key", tmp_path / "tls.crt"
    request = ["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "1"]
    request += ["-subj", "/CN=yarf", "-addext", "subjectAltName=DNS:localhost"]
    subprocess.run(
        [*request, "-keyout", str(key), "-out", str(cert)], capture_output=True, check=True
    )
    credentials = grpc.ssl_server_credentials([(key.read_bytes(), cert.read_bytes())])
    server, port = health_server(serving=True, credentials=credentials)
    try:
        secure = run_probe(f"localhost:{port}", str(cert))
        plaintext = run_probe(f"localhost:{port}")
    finally:
        server.stop(None)
    assert secure.returncode == 0, secure.stderr
    assert plaintext.returncode == 1
