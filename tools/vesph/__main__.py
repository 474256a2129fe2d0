"""`python3 -m vesph TOOL [ARGS]` (what tools/vesph-post runs): TOOL is a tool's name (as
listed without arguments) or its module (vesph.measure.drop or measure.drop)."""
import importlib
import sys

from vesph import TOOL_MODULES


def usage(out):
    print("usage: vesph-post TOOL [ARGS...]   (TOOL --help for its arguments)\n\ntools:", file=out)
    for name, module in TOOL_MODULES.items():
        print(f"  {name:28s} python3 -m {module}", file=out)


def main():
    if len(sys.argv) < 2 or sys.argv[1] in ("-h", "--help"):
        usage(sys.stdout if len(sys.argv) >= 2 else sys.stderr)
        return 0 if len(sys.argv) >= 2 else 2
    tool = sys.argv[1]
    module = TOOL_MODULES.get(tool.removesuffix(".py"))
    if module is None:
        candidate = tool if tool.startswith("vesph.") else "vesph." + tool
        module = candidate if candidate in TOOL_MODULES.values() else None
    if module is None:
        print(f"vesph-post: unknown tool {tool!r}", file=sys.stderr)
        usage(sys.stderr)
        return 2
    # the tool's messages name it as its old script did (argparse takes sys.argv[0])
    name = next((n for n, m in TOOL_MODULES.items() if m == module), tool)
    sys.argv = [name + ".py"] + sys.argv[2:]
    return importlib.import_module(module).main()


if __name__ == "__main__":
    sys.exit(main())
