#!/usr/bin/python3
"""Writes docs/job-reference.md from the JSON schemas in schemas/, so the reference cannot drift from them.

    docs/tools/gen_job_reference.py            # rewrites docs/job-reference.md
    docs/tools/gen_job_reference.py --check    # exit 1 (and a diff) when the committed file is not current

Every key of a job (schemas/job.schema.json and the files it references), of each method's bake entry
(schemas/methods/<method>.schema.json), of a suite and of report.json is one table row: its type and range as
the schema states them and its description. Only the standard library; run with Debian's /usr/bin/python3.
"""
import argparse
import difflib
import json
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCHEMAS = os.path.join(ROOT, "schemas")
OUTPUT = os.path.join(ROOT, "docs", "job-reference.md")


class Schemas:
    def __init__(self):
        self.docs = {}

    def load(self, name):
        if name not in self.docs:
            path = os.path.join(SCHEMAS, name)
            if not os.path.exists(path):
                path = os.path.join(SCHEMAS, "methods", name)
            with open(path, encoding="utf-8") as f:
                self.docs[name] = json.load(f)
        return self.docs[name]

    def resolve(self, node, current):
        """Follows $ref to (node, file it lives in, definition name or None)."""
        name = None
        for _ in range(16):
            if not (isinstance(node, dict) and "$ref" in node):
                break
            ref = node["$ref"]
            file, _, pointer = ref.partition("#")
            if file:
                current = file
                name = file
            target = self.load(current)
            for part in [p for p in pointer.split("/") if p]:
                target = target[part]
            if pointer:
                name = pointer.split("/")[-1]
            # A $ref beside its own description keeps that description.
            extra = {k: v for k, v in node.items() if k != "$ref"}
            node = dict(target, **extra) if extra else target
        return node, current, name


def number(v):
    """1e6 rather than 1000000.0: the way the schemas and people write it."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return json.dumps(v)
    if isinstance(v, int) and abs(v) < 100000:
        return str(v)
    text = f"{v:g}"
    return text.replace("e+0", "e").replace("e+", "e").replace("e-0", "e-")


def number_range(node):
    lo, hi = node.get("minimum"), node.get("maximum")
    xlo, xhi = node.get("exclusiveMinimum"), node.get("exclusiveMaximum")
    fmt = number
    if lo is None and xlo is None and hi is None and xhi is None:
        return ""
    left = f"[{fmt(lo)}" if lo is not None else (f"({fmt(xlo)}" if xlo is not None else "(-inf")
    right = f"{fmt(hi)}]" if hi is not None else (f"{fmt(xhi)})" if xhi is not None else "inf)")
    return f" in {left}, {right}"


def type_text(schemas, node, current, sections):
    node, current, name = schemas.resolve(node, current)
    if not isinstance(node, dict):
        return ""
    if "const" in node:
        return f"`{json.dumps(node['const'])}`"
    if "enum" in node:
        return "one of " + ", ".join(f"`{json.dumps(v) if not isinstance(v, str) else v}`" for v in node["enum"])
    if "oneOf" in node and "type" not in node:
        parts = [type_text(schemas, alt, current, sections) for alt in node["oneOf"]]
        parts = [p for p in parts if p]
        return " or ".join(dict.fromkeys(parts))
    t = node.get("type")
    if t in ("number", "integer"):
        return t + number_range(node)
    if t == "string":
        return "string" + (f" matching `{node['pattern']}`" if "pattern" in node else "")
    if t == "boolean":
        return "boolean"
    if t == "array":
        inner = type_text(schemas, node.get("items", {}), current, sections)
        count = ""
        if node.get("minItems") is not None and node.get("minItems") == node.get("maxItems"):
            count = f" {node['minItems']}"
        elif node.get("minItems"):
            count = f" (at least {node['minItems']})"
        return f"array{count} of {inner}" if inner else f"array{count}"
    if t == "object" or "properties" in node:
        if name in sections:
            return f"object ([{sections[name]}](#{anchor(sections[name])}))"
        if "additionalProperties" in node and isinstance(node["additionalProperties"], dict):
            return "object: key -> " + type_text(schemas, node["additionalProperties"], current, sections)
        return "object"
    return ""


def anchor(title):
    keep = "".join(c for c in title.lower() if c.isalnum() or c in " -_")
    return keep.replace(" ", "-")


def cell(text):
    """A table cell: no raw HTML (<name> would vanish), no emphasis from a glob's *; code spans as written."""
    parts = text.replace("\n", " ").split("`")
    for i, part in enumerate(parts):
        if i % 2 == 0:
            part = part.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace("*", "\\*")
        parts[i] = part.replace("|", "\\|")
    return "`".join(parts)


def table(schemas, node, current, sections, pointer):
    node, current, _ = schemas.resolve(node, current)
    required = set(node.get("required", []))
    lines = ["| key | type | meaning |", "|---|---|---|"]
    for key, sub in node.get("properties", {}).items():
        resolved, _, _ = schemas.resolve(sub, current)
        desc = sub.get("description") or (resolved.get("description") if isinstance(resolved, dict) else "") or ""
        req = " **(required)**" if key in required else ""
        lines.append(f"| `{pointer}{key}`{req} | {cell(type_text(schemas, sub, current, sections))} | {cell(desc)} |")
    return lines


def section(out, schemas, title, file, node_path, pointer, sections, level="###"):
    node = schemas.load(file)
    for part in node_path:
        node = node[part]
    node, current, _ = schemas.resolve(node, file)
    out.append(f"{level} {title}")
    out.append("")
    if node.get("description"):
        out.append(node["description"])
        out.append("")
    out.extend(table(schemas, node, current, sections, pointer))
    out.append("")


def generate():
    s = Schemas()
    job = s.load("job.schema.json")
    # Definitions with their own section, by the name their $ref ends in.
    sections = {
        "height": "height", "procedural": "height.procedural", "surface": "surface",
        "surface_image": "surface images", "light": "lights[]", "output": "output", "texture": "output.textures[]",
        "report": "report", "environment.schema.json": "environment", "reference.schema.json": "reference",
        "bake_entry": "bake entries",
    }
    out = [
        "# Job reference",
        "",
        "<!-- Generated by docs/tools/gen_job_reference.py from schemas/; do not edit by hand. -->",
        "",
        "Every key hfbake accepts, from the JSON schemas it validates against (`schemas/`). Unknown keys are",
        "errors. Paths are relative to the file that names them. An integer is written without a fraction or",
        "an exponent (`16`, not `16.0` or `1.6e1`, which are refused as not integers). A walk-through of a job is in",
        "[contract.md](contract.md); what the numbers mean is in [methods/](methods/README.md).",
        "",
        "Contents: [job](#job), [height](#height), [height.procedural](#heightprocedural), [surface](#surface),",
        "[environment](#environment), [lights[]](#lights), [reference](#reference), [output](#output),",
        "[output.textures[]](#outputtextures), [report](#report), [bake entries](#bake-entries) ("
        + ", ".join(f"[{m}](#{m})" for m in method_names()) + "), [suite](#suite), [report.json](#reportjson).",
        "",
        "## Job",
        "",
    ]
    section(out, s, "job", "job.schema.json", [], "", sections)
    section(out, s, "height", "job.schema.json", ["definitions", "height"], "height.", sections)
    section(out, s, "height.procedural", "job.schema.json", ["definitions", "procedural"], "height.procedural.",
            sections)
    section(out, s, "surface", "job.schema.json", ["definitions", "surface"], "surface.", sections)
    section(out, s, "surface images", "job.schema.json", ["definitions", "surface_image"], "", sections)
    section(out, s, "environment", "environment.schema.json", [], "environment.", sections)
    section(out, s, "environment.sky", "environment.schema.json", ["properties", "sky"], "environment.sky.",
            sections)
    section(out, s, "environment.sky.sun", "environment.schema.json", ["properties", "sky", "properties", "sun"],
            "environment.sky.sun.", sections)
    section(out, s, "lights[]", "job.schema.json", ["definitions", "light", "properties", "directional"],
            "lights[].directional.", sections)
    section(out, s, "reference", "reference.schema.json", [], "reference.", sections)
    section(out, s, "output", "job.schema.json", ["definitions", "output"], "output.", sections)
    section(out, s, "output.textures[]", "job.schema.json", ["definitions", "texture"], "", sections)
    section(out, s, "report", "job.schema.json", ["definitions", "report"], "report.", sections)
    out += ["## Bake entries", "",
            "Each entry of `bake` names a method; the rest of the entry is validated against that method's",
            "schema, `schemas/methods/<method>.schema.json`. A numeric parameter given as a list is a sweep (see",
            "`bake` above).", ""]
    common = s.load("obscurance_common.schema.json")
    for m in method_names():
        section(out, s, m, f"{m}.schema.json", [], "", sections)
    out += ["### Keys shared by the obscurance methods", "", common["description"], "",
            "| key | type | meaning |", "|---|---|---|"]
    for key, sub in common["definitions"].items():
        out.append(f"| `{key}` | {cell(type_text(s, sub, 'obscurance_common.schema.json', sections))} | "
                   f"{cell(sub.get('description', ''))} |")
    out += ["", "## Suite", ""]
    section(out, s, "suite", "suite.schema.json", [], "", sections)
    out += ["## report.json", ""]
    section(out, s, "report.json", "report.schema.json", [], "", sections)
    report = s.load("report.schema.json")
    for key, sub in report.get("properties", {}).items():
        node, current, _ = s.resolve(sub, "report.schema.json")
        if isinstance(node, dict) and node.get("properties"):
            section(out, s, f"report.json {key}", "report.schema.json", ["properties", key], f"{key}.", sections,
                    level="####")
    for key, sub in report.get("definitions", {}).items():
        if isinstance(sub, dict) and sub.get("properties"):
            section(out, s, f"report.json: {key}", "report.schema.json", ["definitions", key], "", sections,
                    level="####")
    while out and out[-1] == "":
        out.pop()
    return "\n".join(out) + "\n"


def method_names():
    order = ["p1", "p2", "nlp", "hbao", "lsao", "farfield", "hsao", "vo", "relief"]
    found = sorted(f[: -len(".schema.json")] for f in os.listdir(os.path.join(SCHEMAS, "methods"))
                   if f.endswith(".schema.json") and f != "obscurance_common.schema.json")
    return [m for m in order if m in found] + [m for m in found if m not in order]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="compare with the committed file instead of writing")
    parser.add_argument("--output", default=OUTPUT)
    args = parser.parse_args()
    text = generate()
    if args.check:
        try:
            with open(args.output, encoding="utf-8") as f:
                old = f.read()
        except FileNotFoundError:
            old = ""
        if old != text:
            sys.stdout.writelines(difflib.unified_diff(old.splitlines(True), text.splitlines(True),
                                                       args.output, "generated from schemas/"))
            print(f"{args.output} is not current: run docs/tools/gen_job_reference.py and commit the result",
                  file=sys.stderr)
            return 1
        return 0
    with open(args.output, "w", encoding="utf-8") as f:
        f.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
