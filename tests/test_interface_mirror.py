"""The C++ interfaces mirror the proto services, as read from both declarations.

The rule is in tests/interface_mirror.py. The drift tests change copies of
the headers and protos, never the real ones.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest
from interface_mirror import (
    CppInterface,
    mirror_mismatches,
    read_cpp_interfaces,
    read_proto_services,
)

REPO = Path(__file__).resolve().parents[1]
INCLUDE = REPO / "server" / "include"
PROTO = REPO / "proto"


@pytest.fixture(scope="module")
def interfaces() -> list[CppInterface]:
    return read_cpp_interfaces(INCLUDE)


@pytest.fixture(scope="module")
def services() -> dict[str, tuple[str, ...]]:
    return read_proto_services(PROTO)


def copy_tree(source: Path, to: Path) -> Path:
    shutil.copytree(source, to)
    return to


def replace_once(path: Path, old: str, new: str) -> None:
    text = path.read_text()
    assert text.count(old) == 1, f"{path.name} no longer has {old!r} once"
    path.write_text(text.replace(old, new))


def test_every_cpp_interface_mirrors_its_proto_service(
    interfaces: list[CppInterface], services: dict[str, tuple[str, ...]]
) -> None:
    mismatches = mirror_mismatches(interfaces, services)
    assert not mismatches, "C++ interfaces and proto services differ:\n" + "\n".join(mismatches)


def test_every_class_that_declares_kinterface_is_read(interfaces: list[CppInterface]) -> None:
    # Counted in the text, apart from the parser, so a class it misses cannot pass unseen.
    declared = re.compile(r"static\s+constexpr\s+[^;]*\bkInterface\s*=")
    in_text = sum(len(declared.findall(h.read_text())) for h in (INCLUDE / "yarf").glob("*.h"))
    assert len(interfaces) == in_text
    assert all(interface.methods for interface in interfaces)


def test_a_virtual_method_without_an_rpc_is_reported(
    tmp_path: Path, services: dict[str, tuple[str, ...]]
) -> None:
    include = copy_tree(INCLUDE, tmp_path / "include")
    replace_once(
        include / "yarf" / "texture.h",
        "  virtual uint32_t Channels() const = 0;\n",
        "  virtual uint32_t Channels() const = 0;\n  virtual float Roughness() const = 0;\n",
    )
    mismatches = mirror_mismatches(read_cpp_interfaces(include), services)
    assert len(mismatches) == 1, mismatches
    assert "Texture::Roughness (texture.h:" in mismatches[0]
    assert "has no rpc yarf.v1.Texture.Roughness" in mismatches[0]


def test_a_virtual_method_inherited_from_a_helper_base_is_checked(
    tmp_path: Path, services: dict[str, tuple[str, ...]]
) -> None:
    include = copy_tree(INCLUDE, tmp_path / "include")
    replace_once(
        include / "yarf" / "texture.h",
        "class Texture : public virtual Component {",
        "class Prefetching {\n public:\n  virtual ~Prefetching() = default;\n"
        "  virtual void Prefetch() const = 0;\n};\n\n"
        "class Texture : public Prefetching, public virtual Component {",
    )
    mismatches = mirror_mismatches(read_cpp_interfaces(include), services)
    assert len(mismatches) == 1, mismatches
    assert "has no rpc yarf.v1.Texture.Prefetch" in mismatches[0]


def test_an_rpc_without_a_cpp_method_is_reported(
    tmp_path: Path, interfaces: list[CppInterface]
) -> None:
    proto = copy_tree(PROTO, tmp_path / "proto")
    replace_once(
        proto / "yarf" / "v1" / "texture.proto",
        "  rpc Mean(MeanRequest) returns (MeanReply);\n",
        "  rpc Mean(MeanRequest) returns (MeanReply);\n"
        "  rpc Gradient(MeanRequest) returns (MeanReply);\n",
    )
    mismatches = mirror_mismatches(interfaces, read_proto_services(proto))
    assert len(mismatches) == 1, mismatches
    assert mismatches[0].startswith(
        "rpc yarf.v1.Texture.Gradient has no C++ method in Texture (texture.h:"
    )


def test_a_method_that_names_a_missing_rpc_is_reported(
    tmp_path: Path, services: dict[str, tuple[str, ...]]
) -> None:
    include = copy_tree(INCLUDE, tmp_path / "include")
    replace_once(
        include / "yarf" / "math.h",
        "  // rpc: Signature\n  virtual uint32_t DomainDimensions",
        "  // rpc: Signatures\n  virtual uint32_t DomainDimensions",
    )
    mismatches = mirror_mismatches(read_cpp_interfaces(include), services)
    assert len(mismatches) == 1, mismatches
    assert "Warp::DomainDimensions (math.h:" in mismatches[0]
    assert "says it serves yarf.v1.Warp.Signatures, no such rpc" in mismatches[0]


def test_in_process_only_says_why(tmp_path: Path, services: dict[str, tuple[str, ...]]) -> None:
    include = copy_tree(INCLUDE, tmp_path / "include")
    replace_once(
        include / "yarf" / "texture.h",
        "  virtual uint32_t Channels() const = 0;\n",
        "  virtual uint32_t Channels() const = 0;\n"
        "  // in-process only:\n  virtual float Roughness() const = 0;\n",
    )
    mismatches = mirror_mismatches(read_cpp_interfaces(include), services)
    assert len(mismatches) == 1, mismatches
    assert "Texture::Roughness" in mismatches[0]
    assert "`in-process only:` says no why" in mismatches[0]


def test_a_service_that_kinterface_names_must_exist(
    tmp_path: Path, services: dict[str, tuple[str, ...]]
) -> None:
    include = copy_tree(INCLUDE, tmp_path / "include")
    replace_once(include / "yarf" / "texture.h", '"yarf.v1.Texture"', '"yarf.v1.Textures"')
    mismatches = mirror_mismatches(read_cpp_interfaces(include), services)
    assert len(mismatches) == 1, mismatches
    assert "Texture (texture.h:" in mismatches[0]
    assert "kInterface names yarf.v1.Textures, no service of the IDL" in mismatches[0]
