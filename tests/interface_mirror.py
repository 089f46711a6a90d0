"""The C++ interfaces (server/include/yarf/*.h) against the proto services they mirror.

An interface is a class that names its service in `kInterface`. Each of its
virtual methods serves the rpc of the same name, unless the comment above it
has a line `rpc: Name[, Name]` (the rpcs it serves instead) or
`in-process only: why` (it serves none). Every rpc must be served by some
method. Both sides are read from their declarations: the headers through
libclang, the services from the .proto files through protoc.
"""

from __future__ import annotations

import re
import tempfile
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import clang.cindex as clang
from google.protobuf import descriptor_pb2
from grpc_tools import protoc

# A line of a method's comment that says which rpcs it serves, or that it serves none.
RPC_LINE = re.compile(r"^rpc:\s*(?P<names>.*)$")
IN_PROCESS_LINE = re.compile(r"^in-process only:\s*(?P<why>.*)$")
RPC_NAME = re.compile(r"^[A-Za-z_]\w*$")

# Stands in for the interface_version.h CMake generates: the headers include it.
GENERATED_VERSION_HEADER = '#define YARF_INTERFACE_VERSION "0"\n'


@dataclass(frozen=True)
class CppMethod:
    name: str
    # Where it is declared, file:line.
    location: str
    # The rpcs it serves: its own name unless its comment names others; none when in process only.
    rpcs: tuple[str, ...]
    in_process_only: bool
    # Annotations that could not be read, said as a reader should fix them.
    problems: tuple[str, ...]


@dataclass(frozen=True)
class CppInterface:
    class_name: str
    # The proto service's full name (kInterface).
    service: str
    location: str
    methods: tuple[CppMethod, ...]


def clang_resource_dir() -> Path:
    """Clang's own headers (stddef.h...), which the libclang wheel does not ship.

    `make deps` installs clang from Debian, whose resource directory has them.
    """
    found = sorted(
        Path("/usr/lib").glob("llvm-*/lib/clang/*/include/stddef.h"),
        key=lambda p: [int(part) for part in re.findall(r"\d+", str(p.parent.parent))],
    )
    if not found:
        raise RuntimeError("no clang resource directory under /usr/lib/llvm-*: run `make deps`")
    return found[-1].parent.parent


def read_cpp_interfaces(include_dir: Path) -> list[CppInterface]:
    """Every class of include_dir/yarf/*.h that declares kInterface, with its virtual methods."""
    header_dir = (include_dir / "yarf").resolve()
    headers = sorted(header_dir.glob("*.h"))
    main = "/yarf-mirror/all_headers.cc"
    generated = "/yarf-mirror/generated"
    source = "".join(f'#include "yarf/{header.name}"\n' for header in headers)
    unit = clang.Index.create().parse(
        main,
        args=[
            "-x",
            "c++",
            "-std=c++20",
            f"-I{include_dir}",
            f"-I{generated}",
            "-resource-dir",
            str(clang_resource_dir()),
            # So that plain // comments are attached to the declarations below them.
            "-fparse-all-comments",
        ],
        unsaved_files=[
            (main, source),
            (f"{generated}/yarf/interface_version.h", GENERATED_VERSION_HEADER),
        ],
        options=clang.TranslationUnit.PARSE_SKIP_FUNCTION_BODIES,
    )
    errors = [str(d) for d in unit.diagnostics if d.severity >= clang.Diagnostic.Error]
    if errors:
        raise RuntimeError("the interface headers do not parse:\n" + "\n".join(errors))

    classes = [c for c in _class_definitions(unit.cursor) if _in_dir(c, header_dir)]
    return [_interface(c) for c in classes if _interface_name(c) is not None]


def read_proto_services(proto_dir: Path) -> dict[str, tuple[str, ...]]:
    """The rpc names of every service of proto_dir/yarf/v1/*.proto, by full service name."""
    well_known = resources.files("grpc_tools") / "_proto"
    protos = sorted(str(p) for p in (proto_dir / "yarf" / "v1").glob("*.proto"))
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "yarf.binpb"
        args = ["protoc", f"-I{proto_dir}", f"-I{well_known}", f"--descriptor_set_out={out}"]
        if protoc.main([*args, *protos]) != 0:
            raise RuntimeError(f"protoc could not read {proto_dir}/yarf/v1/*.proto")
        files = descriptor_pb2.FileDescriptorSet.FromString(out.read_bytes()).file
    return {
        f"{file.package}.{service.name}": tuple(method.name for method in service.method)
        for file in files
        for service in file.service
    }


def mirror_mismatches(
    interfaces: Sequence[CppInterface], services: Mapping[str, Sequence[str]]
) -> list[str]:
    """Every way the interfaces and their services differ, one sentence each."""
    found: list[str] = []
    for interface in interfaces:
        who = f"{interface.class_name} ({interface.location})"
        rpcs = services.get(interface.service)
        if rpcs is None:
            found.append(f"{who}: kInterface names {interface.service}, no service of the IDL")
            continue
        served: set[str] = set()
        for method in interface.methods:
            where = f"{interface.class_name}::{method.name} ({method.location})"
            found += [f"{where}: {problem}" for problem in method.problems]
            for rpc in method.rpcs:
                if rpc in rpcs:
                    served.add(rpc)
                elif method.rpcs == (method.name,):
                    found.append(
                        f"{where} has no rpc {interface.service}.{rpc}: add the rpc, or say"
                        " `rpc: Name` or `in-process only: why` in the comment above it"
                    )
                else:
                    found.append(f"{where} says it serves {interface.service}.{rpc}, no such rpc")
        found += [
            f"rpc {interface.service}.{rpc} has no C++ method in {who}: add one, or say"
            f" `rpc: {rpc}` above the method that serves it"
            for rpc in rpcs
            if rpc not in served
        ]
    return found


def _class_definitions(cursor: clang.Cursor) -> Iterator[clang.Cursor]:
    for child in cursor.get_children():
        if child.kind == clang.CursorKind.NAMESPACE:
            yield from _class_definitions(child)
        elif child.kind in (clang.CursorKind.CLASS_DECL, clang.CursorKind.STRUCT_DECL):
            if child.is_definition():
                yield child
                yield from _class_definitions(child)


def _in_dir(cursor: clang.Cursor, directory: Path) -> bool:
    file = cursor.location.file
    return file is not None and Path(file.name).resolve().parent == directory


def _where(cursor: clang.Cursor) -> str:
    return f"{Path(cursor.location.file.name).name}:{cursor.location.line}"


def _interface_name(cls: clang.Cursor) -> str | None:
    """kInterface's string when the class itself declares it."""
    for child in cls.get_children():
        if child.kind == clang.CursorKind.VAR_DECL and child.spelling == "kInterface":
            literals = [t.spelling for t in child.get_tokens() if t.kind == clang.TokenKind.LITERAL]
            if len(literals) != 1 or not literals[0].startswith('"'):
                raise RuntimeError(f"{_where(child)}: kInterface is not one string literal")
            return literals[0].strip('"')
    return None


def _interface(cls: clang.Cursor) -> CppInterface:
    return CppInterface(
        class_name=cls.spelling,
        service=_interface_name(cls) or "",
        location=_where(cls),
        methods=tuple(_virtual_methods(cls)),
    )


def _virtual_methods(cls: clang.Cursor) -> Iterator[CppMethod]:
    """The class's virtual methods and those of its bases, but not of a base that is an
    interface itself: that base's service serves them."""
    inherited_from_interfaces: set[str] = set()
    for child in cls.get_children():
        if child.kind != clang.CursorKind.CXX_BASE_SPECIFIER:
            continue
        base = child.type.get_declaration().get_definition()
        if base is None:
            continue
        if _interface_name(base) is not None:
            inherited_from_interfaces |= {m.name for m in _virtual_methods(base)}
        else:
            yield from _virtual_methods(base)
    for child in cls.get_children():
        if child.kind == clang.CursorKind.CXX_METHOD and child.is_virtual_method():
            if child.spelling not in inherited_from_interfaces:
                yield _method(child)


def _method(cursor: clang.Cursor) -> CppMethod:
    name = cursor.spelling
    rpcs: list[str] = []
    in_process_only = False
    problems: list[str] = []
    for line in (cursor.raw_comment or "").splitlines():
        text = line.strip().lstrip("/").strip()
        if match := RPC_LINE.match(text):
            names = [n.strip() for n in match["names"].split(",")]
            rpcs += names
            problems += [
                f"`rpc:` names {n!r}, not an rpc name" for n in names if not RPC_NAME.match(n)
            ]
        elif match := IN_PROCESS_LINE.match(text):
            in_process_only = True
            if not match["why"].strip():
                problems.append("`in-process only:` says no why")
    if in_process_only and rpcs:
        problems.append("says both `rpc:` and `in-process only:`")
    if not in_process_only and not rpcs:
        rpcs = [name]
    return CppMethod(
        name=name,
        location=_where(cursor),
        rpcs=tuple(r for r in rpcs if RPC_NAME.match(r)) if not in_process_only else (),
        in_process_only=in_process_only,
        problems=tuple(problems),
    )
