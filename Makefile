# The two commands: `make demo` and `make test` (each installs what it needs first).
.PHONY: all deps build test test-sanitize demo format lint clean

SHELL := /bin/bash
REPO := $(CURDIR)

all: build

deps:
	@bash scripts/install_deps.sh

build: deps
	@bash scripts/ws.sh build

test: deps
	@bash scripts/ws.sh test

# The core libraries (ebslam, dasp, eDVS core) in Debug with ASan + UBSan, and their tests.
test-sanitize: deps
	@bash scripts/test_sanitize.sh

demo: deps
	@bash scripts/ws.sh build
	@bash scripts/demo.sh

# clang-format in place on all project C++.
format:
	@git ls-files '*.cpp' '*.h' '*.hpp' | xargs -r clang-format -i

# clang-format check plus cppcheck on project C++ (exit non-zero on findings).
lint:
	@bash scripts/lint.sh

clean:
	rm -rf .ws demo_output compile_commands.json
