"""Emits the SDK's public model of the robot state (sdk/core RobotState.kt): what users of the SDK see instead of
the wire structs of sdk/protocol.

- Every enum the state or the SDK's API uses becomes an SDK enum of the same name, its values in schema order plus
  UNKNOWN (a code this SDK does not know: a newer robot); the wire code stays internal.
- Every flag set becomes an enum of its bits (`line_flags` -> `LineFlag`), and a flags field a `Set` of them.
- `robot_state` becomes `RobotState`, each group a nested class (`state.line` is a `RobotState.Line`), each field a
  property named by the camelCase of the schema name, typed by its meaning (enum, flag set, Int, Long, List<Int>).
- The mapping wire -> model (`toModel()`) is generated beside them: the two cannot drift.

The classes have internal constructors and no `copy`/`componentN`: a field added to the schema breaks no caller.
"""

import textwrap

from .model import HEADER, PRIMS, camel

OUT = "sdk/core/src/commonMain/kotlin/org/pocketbot/sdk/RobotState.kt"
WIRE = "org.pocketbot.protocol"

# Enums the SDK's API uses beyond those of the state (commands, errors, debug text, IR messages, movement results).
API_ENUMS = ["sync_mode", "colour_mode", "side", "error_code", "debug_module", "movement_outcome"]

# SDK-only values, in place of UNKNOWN: what a code the SDK does not know, or no code at all, means there.
EXTRA = {
    "movement_outcome": ("lost", "The robot no longer holds it and has no record of how it ended: it restarted (see "
                                 "[RobotEvent.Restarted]), or its log no longer goes back that far, or it reported an "
                                 "outcome this SDK does not know. [MovementResult.done] is what this host saw it do, "
                                 "when it saw it run"),
}


def _sentence(text):
    text = text.strip()
    return text[:1].upper() + text[1:] + ("" if text.endswith(".") else ".")


def _kdoc(text, indent):
    """A KDoc comment, on one line when it fits in 120 columns, else wrapped."""
    one = f"{indent}/** {text} */"
    if len(one) <= 120:
        return [one]
    return [f"{indent}/**"] + [f"{indent} * {line}" for line in textwrap.wrap(text, 116 - len(indent))] + [f"{indent} */"]


def flag_class(name):
    return camel(name[:-1] if name.endswith("s") else name, True)


def _enum(name, e):
    cls = camel(name, True)
    docs = e.get("docs", {})
    extra, extra_doc = EXTRA.get(name, ("unknown", "A code this SDK does not know (a newer robot sent it)"))
    o = _kdoc(_sentence(e.get("doc", "")), "") + [f"public enum class {cls}(internal val code: Int) {{"]
    # An enum with a value of that name (colour's `unknown`) takes the codes it does not know as that value.
    entries = list(e["values"].items()) + ([] if extra in e["values"] else [(extra, -1)])
    for i, (k, v) in enumerate(entries):
        doc = docs.get(k) or (extra_doc if k == extra and k not in e["values"] else None)
        if k == extra and k in e["values"] and not doc:
            doc = "Not known to the robot, or a code this SDK does not know (a newer robot sent it)"
        if doc:
            o += _kdoc(_sentence(doc), "    ")
        o.append(f"    {k.upper()}({v})" + (";" if i == len(entries) - 1 else ","))
    o += ["", "    internal companion object {",
          f"        /** The value with this wire code; [{extra.upper()}] for a code this SDK does not know. */",
          f"        fun fromCode(code: Int): {cls} = when (code) {{"]
    for k, v in e["values"].items():
        o.append(f"            {v} -> {k.upper()}")
    o += [f"            else -> {extra.upper()}", "        }", "    }", "}"]
    return o


def _flags(name, fl):
    cls = flag_class(name)
    docs = fl.get("docs", {})
    values = list(fl["values"].items())
    o = _kdoc(f"{_sentence(fl.get('doc', ''))} A flags field of the state is a `Set` of these.", "")
    o.append(f"public enum class {cls}(internal val mask: Int) {{")
    for i, (k, v) in enumerate(values):
        if k in docs:
            o += _kdoc(_sentence(docs[k]), "    ")
        o.append(f"    {k.upper()}(0x{v:02X})" + (";" if i == len(values) - 1 else ","))
    o += ["", "    internal companion object {",
          "        // Every combination of the bits, made once: a state update allocates no set.",
          f"        private val sets: List<Set<{cls}>> = List(1 shl entries.size) {{ bits ->",
          "            entries.filterIndexedTo(LinkedHashSet()) { i, _ -> bits and (1 shl i) != 0 }",
          "        }",
          "",
          "        /** The flags set in [mask]; bits this SDK does not know are left out. */",
          f"        fun of(mask: Int): Set<{cls}> {{",
          "            var bits = 0",
          "            entries.forEachIndexed { i, f -> if (mask and f.mask != 0) bits = bits or (1 shl i) }",
          "            return sets[bits]",
          "        }",
          "    }",
          "}"]
    return o


def _kt_type(f, nested=()):
    """The property type; an enum named like a nested class (the enum Colour, the group RobotState.Colour) is
    written with its package."""
    if f.enum:
        name = camel(f.enum, True)
        return f"org.pocketbot.sdk.{name}" if name in nested else name
    if f.flags:
        return f"Set<{flag_class(f.flags)}>"
    if f.is_struct:
        return f.struct.kt_name.removeprefix("State")
    t = PRIMS[f.base][3]
    t = "Double" if t == "Float" else t
    return f"List<{t}>" if f.count else t


def _to_model(f, expr):
    if f.enum:
        return f"{camel(f.enum, True)}.fromCode({expr}.code)"
    if f.flags:
        return f"{flag_class(f.flags)}.of({expr})"
    if f.is_struct:
        return f"{expr}.toModel()"
    if f.base == "f32":
        return f"{expr}.toDouble()"
    return expr


def _doc(f, indent):
    unit = f", in {f.unit}" if f.unit else ""
    return _kdoc(_sentence(f.doc + unit), indent)


def _nested(s, name, doc, nested):
    """A state group (or shared struct) as a class nested in RobotState."""
    fields = s.fields
    o = _kdoc(_sentence(doc), "    ") + [f"    public class {name} internal constructor("]
    for f in fields:
        o += _doc(f, "        ")
        o.append(f"        public val {camel(f.name)}: {_kt_type(f, nested)},")
    o += ["    ) {",
          "        override fun equals(other: Any?): Boolean =",
          f"            this === other || other is {name} && " + " && ".join(
              f"{camel(f.name)} == other.{camel(f.name)}" for f in fields),
          "",
          "        override fun hashCode(): Int {",
          f"            var h = {camel(fields[0].name)}.hashCode()"]
    o += [f"            h = 31 * h + {camel(f.name)}.hashCode()" for f in fields[1:]]
    o += ["            return h", "        }", "",
          f"        override fun toString(): String = \"{name}(" + ", ".join(
              f"{camel(f.name)}=${camel(f.name)}" for f in fields) + ")\"",
          "    }"]
    return o


def _mapping(s, name):
    args = ", ".join(_to_model(f, camel(f.name)) for f in s.fields)
    return [f"internal fun {WIRE}.{s.kt_name}.toModel(): RobotState.{name} = RobotState.{name}({args})"]


def emit(model):
    schema = model.schema
    state = model.state
    enums = []
    for s in [state] + [g.struct for g in model.state_groups] + [f.struct for g in model.state_groups
                                                                 for f in g.struct.fields if f.is_struct]:
        enums += [f.enum for f in s.fields if f.enum and f.enum not in enums]
    enums += [e for e in API_ENUMS if e not in enums]
    flags = [name for name in model.flags]
    # The shared structs the state's groups use (proximity_side), then the groups, in schema order.
    shared = []
    for g in model.state_groups:
        for f in g.struct.fields:
            if f.is_struct and f.struct not in shared:
                shared.append(f.struct)
    nested = {sh.kt_name for sh in shared} | {g.struct.kt_name.removeprefix("State") for g in model.state_groups}

    o = [f"// {HEADER}", "package org.pocketbot.sdk", ""]
    o += ["/**",
          " * The whole robot state as the SDK mirrors it ([Robot.state]): one group per firmware module, one property per",
          " * field of the protocol's `robot_state`, named by its camelCase (`wheels.speed_left_mmps` is",
          " * `wheels.speedLeftMmps`); codes are enums, flag bits sets of enums.",
          " *",
          " * ```",
          " * val s = robot.state.value",
          " * if (LineFlag.SEEN in s.line.flags) println(\"line at ${s.line.position} permille\")",
          " * if (s.locomotion.mode == LocoMode.FAILSAFE) println(\"the robot stopped on its own\")",
          " * ```",
          " * Generated from protocol/pocketbot.toml, as the wire codecs are.",
          " */",
          "public class RobotState internal constructor("]
    for f in state.fields:
        o += _doc(f, "    ")
        o.append(f"    public val {camel(f.name)}: {_kt_type(f)},")
    o += [") {"]
    for sh in shared:
        o += _nested(sh, sh.kt_name, sh.doc, nested) + [""]
    for g in model.state_groups:
        o += _nested(g.struct, g.struct.kt_name.removeprefix("State"), g.doc, nested) + [""]
    names = [camel(f.name) for f in state.fields]
    o += ["    override fun equals(other: Any?): Boolean =",
          "        this === other || other is RobotState && " + " && ".join(f"{n} == other.{n}" for n in names),
          "",
          "    override fun hashCode(): Int {",
          f"        var h = {names[0]}.hashCode()"]
    o += [f"        h = 31 * h + {n}.hashCode()" for n in names[1:]]
    o += ["        return h", "    }", "",
          "    override fun toString(): String = \"RobotState(" + ", ".join(f"{n}=${n}" for n in names) + ")\"",
          "}", ""]
    for name in enums:
        o += _enum(name, schema["enum"][name]) + [""]
    for name in flags:
        o += _flags(name, model.flags[name]) + [""]
    o += ["// The mapping wire -> model: the wire structs of sdk/protocol to the classes above, field by field.", ""]
    o += [f"internal fun {WIRE}.RobotState.toModel(): RobotState = RobotState(" +
          ", ".join(_to_model(f, camel(f.name)) for f in state.fields) + ")", ""]
    for sh in shared:
        o += _mapping(sh, sh.kt_name) + [""]
    for g in model.state_groups:
        o += _mapping(g.struct, g.struct.kt_name.removeprefix("State")) + [""]
    return {OUT: "\n".join(o).rstrip() + "\n"}
