"""Emits the SDK's typed settings tree (sdk/core RobotSettings.kt).

Each settings group becomes a class with one typed property per field (f32 -> DoubleSetting, an `enum` field ->
EnumSetting, arrays -> IntListSetting, char[N] -> TextSetting, other integers -> IntSetting), named by the
camelCase of the schema name (`line_pid.kp` -> `linePid.kp`). Groups of a shared struct type (`type = "pid"`)
share one class.
"""

from .model import HEADER, camel

OUT = "sdk/core/src/commonMain/kotlin/org/pocketbot/sdk/RobotSettings.kt"


def _kdoc(text, indent=""):
    return f"{indent}/** {text} */"


def _describe(f, enums):
    doc = f.get("doc", "")
    doc = doc[:1].upper() + doc[1:] if doc else ""
    bits = []
    if f.get("enum"):
        bits.append("one of " + ", ".join(enums[f["enum"]]["values"]))
    elif "min" in f and "max" in f:
        bits.append(f"{f['min']}..{f['max']}")
    if f.get("unit"):
        bits.append(f["unit"])
    return f"{doc}{' (' + ', '.join(bits) + ')' if bits else ''}. Setting `{{path}}`."


def _leaf(group, f, enums):
    path = f"{group}.{f['name']}"
    t = f["type"]
    name = camel(f["name"])
    if t.startswith("char["):
        return name, "TextSetting", f'text("{path}")', path
    if "[" in t:
        return name, "IntListSetting", f'ints("{path}")', path
    if t == "f32":
        return name, "DoubleSetting", f'double("{path}")', path
    if f.get("enum"):
        e = camel(f["enum"], True)
        return name, f"EnumSetting<{e}>", f'enum("{path}", {e}.entries.filter {{ it.code >= 0 }}) {{ it.code }}', path
    return name, "IntSetting", f'int("{path}")', path


def emit(model):
    schema = model.schema
    header = HEADER
    enums = schema.get("enum", {})
    structs = schema.get("struct", {})
    used_enums = set()
    classes = {}   # class name -> lines
    props = []     # (group doc, group property, class name, constructor args)
    for g in schema["settings"]:
        gname = g["name"]
        if "type" in g:
            cls = camel(g["type"], True) + "Settings"
            fields = structs[g["type"]]["fields"]
            args = f'this, "{gname}"'
            if cls not in classes:
                lines = [_kdoc(structs[g['type']].get('doc', '')),
                         f"public class {cls} internal constructor(s: SettingsBase, group: String) {{"]
                for f in fields:
                    name, typ, make, _ = _leaf("$group", f, enums)
                    lines.append(_kdoc(_describe(f, enums).replace("{path}", f"<group>.{f['name']}"), "    "))
                    lines.append(f"    public val {name}: {typ} = s.{make}")
                    lines.append("")
                lines[-1] = "}"
                classes[cls] = lines
        else:
            cls = camel(gname, True) + "Settings"
            args = "this"
            lines = [_kdoc(g.get("doc", "")), f"public class {cls} internal constructor(s: SettingsBase) {{"]
            for f in g["fields"]:
                name, typ, make, path = _leaf(gname, f, enums)
                if f.get("enum"):
                    used_enums.add(camel(f["enum"], True))
                lines.append(_kdoc(_describe(f, enums).replace("{path}", path), "    "))
                lines.append(f"    public val {name}: {typ} = s.{make}")
                lines.append("")
            lines[-1] = "}"
            classes[cls] = lines
        props.append((g.get("doc", ""), camel(gname), cls, args))

    o = [f"// {header}", "package org.pocketbot.sdk", ""]
    o += ["import org.pocketbot.sdk.internal.SettingsMirror", "import org.pocketbot.sdk.internal.link.LinkPort", ""]
    o += ["/**",
          " * Settings reflection (thesis 6.3, 9.6): a typed tree of every setting of the robot, mirrored on the host.",
          " * Each setting writes itself alone and suspends until the robot acknowledged it:",
          " *",
          " * ```",
          " * robot.settings.linePid.kp.set(1.5)          // the setting line_pid.kp: 4 bytes at its offset",
          " * val kp = robot.settings.linePid.kp.value    // the value the robot confirmed",
          " * robot.settings[\"line_pid.kp\"]               // the same setting by its name",
          " * robot.settings.save()                        // to EEPROM",
          " * ```",
          " * Generated from protocol/pocketbot.toml: one property per group, one per field, in camelCase.",
          " */",
          "public class RobotSettings internal constructor(link: LinkPort, mirror: SettingsMirror) : SettingsBase(link, mirror) {"]
    for doc, prop, cls, args in props:
        o.append(_kdoc(doc, "    "))
        o.append(f"    public val {prop}: {cls} = {cls}({args})")
        o.append("")
    o += ["    init {", "        checkComplete()", "    }", "}", ""]
    for cls in classes.values():
        o += cls + [""]
    return {OUT: "\n".join(o).rstrip() + "\n"}
