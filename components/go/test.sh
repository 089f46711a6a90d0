#!/usr/bin/env bash
# Tests the Go components: builds (build.sh, quick when current), then
# go vet, a gofmt check that fails on any unformatted file, and go test.
# Arguments are passed to go test (e.g. -run Lambertian -v).
set -euo pipefail

MODULE_DIR=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$MODULE_DIR/../.." && pwd)
TOOLS=$ROOT/.tools

"$MODULE_DIR/build.sh"
# shellcheck source=toolchain.sh
source "$MODULE_DIR/toolchain.sh"
find_go
cd "$MODULE_DIR"

"$GO" vet ./...

# Generated code is not ours to format.
unformatted=$(find . -name '*.go' -not -path './gen/*' -print0 | xargs -0 -r "$(dirname "$GO")/gofmt" -l)
if [ -n "$unformatted" ]; then
  echo "not gofmt-formatted (run gofmt -w):" >&2
  echo "$unformatted" >&2
  exit 1
fi

# -count=1: the statistical tests and the socket tests run every time.
"$GO" test -count=1 "$@" ./...
