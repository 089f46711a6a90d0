#!/usr/bin/env bash
# Builds the Go components: finds (or fetches) Go, installs the protoc
# plugins into .tools/bin, generates Go code from proto/ into gen/, and
# builds every command under cmd/ into build/go/bin/. Each step is skipped
# when its result is current, so a second run takes a moment.
#
#   components/go/build.sh          GO=/path/to/go components/go/build.sh
set -euo pipefail

MODULE_DIR=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd -P)
ROOT=$(cd "$MODULE_DIR/../.." && pwd)
TOOLS=$ROOT/.tools
PROTO_DIR=$ROOT/proto
BIN_DIR=$ROOT/build/go/bin

MODULE=yarf.dev/components/go
GEN_PACKAGE=$MODULE/gen/yarfv1
PROTOC_GEN_GO_VERSION=v1.36.11
PROTOC_GEN_GO_GRPC_VERSION=v1.6.1

# shellcheck source=toolchain.sh
source "$MODULE_DIR/toolchain.sh"

# Installs a protoc plugin at a pinned version unless that version is there.
install_plugin() { # binary package version
  local have=""
  if [ -x "$TOOLS/bin/$1" ]; then
    have=$("$TOOLS/bin/$1" --version 2>/dev/null | awk '{ print $NF }')
  fi
  [ "${have#v}" = "${3#v}" ] && return 0
  echo "installing $1 $3"
  GOBIN=$TOOLS/bin "$GO" install "$2@$3"
}

# Regenerates gen/ when the protos, protoc or the plugins changed: a hash
# of all of them is kept in gen/.stamp.
generate() {
  local protos stamp proto
  mapfile -t protos < <(cd "$PROTO_DIR" && find yarf -name '*.proto' | LC_ALL=C sort)
  stamp=$({
    protoc --version
    echo "$PROTOC_GEN_GO_VERSION $PROTOC_GEN_GO_GRPC_VERSION $GEN_PACKAGE"
    (cd "$PROTO_DIR" && sha256sum "${protos[@]}")
  } | sha256sum | cut -d' ' -f1)
  if [ -f gen/.stamp ] && [ "$(cat gen/.stamp)" = "$stamp" ]; then
    return 0
  fi
  echo "generating Go code from proto/"
  local options=(--go_opt="module=$MODULE/gen" --go-grpc_opt="module=$MODULE/gen")
  for proto in "${protos[@]}"; do
    options+=(--go_opt="M$proto=$GEN_PACKAGE;yarfv1" --go-grpc_opt="M$proto=$GEN_PACKAGE;yarfv1")
  done
  rm -rf gen.new
  mkdir -p gen.new
  protoc -I "$PROTO_DIR" \
    --plugin=protoc-gen-go="$TOOLS/bin/protoc-gen-go" \
    --plugin=protoc-gen-go-grpc="$TOOLS/bin/protoc-gen-go-grpc" \
    --go_out=gen.new --go-grpc_out=gen.new "${options[@]}" "${protos[@]}"
  echo "$stamp" >gen.new/.stamp
  rm -rf gen
  mv gen.new gen
}

if ! command -v protoc >/dev/null; then
  echo "build.sh: protoc not found (Debian package protobuf-compiler)" >&2
  exit 1
fi
find_go
cd "$MODULE_DIR"
install_plugin protoc-gen-go google.golang.org/protobuf/cmd/protoc-gen-go "$PROTOC_GEN_GO_VERSION"
install_plugin protoc-gen-go-grpc google.golang.org/grpc/cmd/protoc-gen-go-grpc "$PROTOC_GEN_GO_GRPC_VERSION"
generate
mkdir -p "$BIN_DIR"
# go build relinks only what changed: an up-to-date binary is left alone.
"$GO" build -buildvcs=false -o "$BIN_DIR/" ./cmd/...
