package org.pocketbot.sdk.it

import org.junit.jupiter.api.Test
import org.pocketbot.sdk.Robot
import java.io.File
import java.lang.reflect.Constructor
import java.lang.reflect.Field
import java.lang.reflect.Method
import java.lang.reflect.Modifier
import java.util.zip.ZipFile
import kotlin.test.assertEquals
import kotlin.test.fail

/**
 * The public API of sdk-core is checked in as `sdk/core/api/pocketbot-sdk-core.api` (the format follows
 * kotlinx binary-compatibility-validator dumps: one block per public class, JVM descriptors). A change to the
 * public surface fails this test until the dump is updated on purpose:
 *
 *     mvn -B -pl sdk/jvm test -Dtest=ApiDumpTest -Dpocketbot.api.update=true
 *
 * and the diff of the .api file is reviewed with the change.
 */
class ApiDumpTest {
    private val dumpFile = File(System.getProperty("pocketbot.api.file") ?: "../core/api/pocketbot-sdk-core.api")

    @Test
    fun publicApiMatchesTheCheckedInDump() {
        val actual = dump()
        val update = System.getProperty("pocketbot.api.update") == "true" || System.getenv("POCKETBOT_API_UPDATE") == "1"
        if (update) {
            dumpFile.parentFile.mkdirs()
            dumpFile.writeText(actual)
            println("API dump written to ${dumpFile.canonicalPath}")
            return
        }
        if (!dumpFile.exists()) fail("no API dump at ${dumpFile.canonicalPath}; create it with -Dpocketbot.api.update=true")
        val expected = dumpFile.readText()
        if (expected != actual) {
            val e = expected.lines().toSet()
            val a = actual.lines().toSet()
            val removed = expected.lines().filter { it !in a && it.isNotBlank() }
            val added = actual.lines().filter { it !in e && it.isNotBlank() }
            assertEquals(
                expected, actual,
                "the public API of sdk-core changed (removed ${removed.size}, added ${added.size} lines):\n" +
                    removed.take(20).joinToString("") { "- $it\n" } + added.take(20).joinToString("") { "+ $it\n" } +
                    "If intended, update the dump: mvn -B -pl sdk/jvm test -Dtest=ApiDumpTest -Dpocketbot.api.update=true",
            )
        }
    }

    private fun classNames(): List<String> {
        val location = File(Robot::class.java.protectionDomain.codeSource.location.toURI())
        val names = if (location.isDirectory) {
            location.walkTopDown().filter { it.isFile && it.name.endsWith(".class") }
                .map { it.relativeTo(location).path.replace(File.separatorChar, '/') }.toList()
        } else {
            ZipFile(location).use { zip -> zip.entries().asSequence().map { it.name }.filter { it.endsWith(".class") }.toList() }
        }
        return names.filter { it.startsWith("org/pocketbot/") && !it.contains("META-INF") }
            .map { it.removeSuffix(".class").replace('/', '.') }.sorted()
    }

    private fun visible(modifiers: Int) = Modifier.isPublic(modifiers) || Modifier.isProtected(modifiers)

    // Kotlin compiles `internal` classes and constructors as public JVM members (internal methods get a `$module`
    // suffix). Explicit API mode makes every visibility explicit in the sources, so they are read from there.
    private val sources = File(System.getProperty("pocketbot.api.sources") ?: "../core/src/commonMain/kotlin")
    private val sourceText by lazy { sources.walkTopDown().filter { it.name.endsWith(".kt") }.joinToString("\n") { it.readText() } }
    private val internalClasses by lazy {
        Regex("""\binternal\s+(?:(?:data|sealed|abstract|open|enum|inner|value|fun)\s+)*(?:class|object|interface)\s+(\w+)""")
            .findAll(sourceText).map { it.groupValues[1] }.toSet()
    }
    private val internalConstructors by lazy {
        Regex("""(?:class|object)\s+(\w+)(?:<[^>]*>)?\s+internal\s+constructor""").findAll(sourceText).map { it.groupValues[1] }.toSet()
    }

    // Internal top-level functions and properties are public static methods of the file facade (`BytesKt`), not
    // mangled: read them from the sources too, per file, as "FacadeKt.name" (properties by their getter).
    private val internalTopLevel by lazy {
        sources.walkTopDown().filter { it.name.endsWith(".kt") }.flatMap { file ->
            val facade = file.nameWithoutExtension + "Kt"
            Regex("""(?m)^internal\s+(?:(?:inline|infix|operator|tailrec|suspend|const)\s+)*(fun|val|var)\s+(?:<[^>]*>\s*)?(?:[\w.<>?]+\.)?(\w+)""")
                .findAll(file.readText()).map { m ->
                    val name = m.groupValues[2]
                    "$facade." + if (m.groupValues[1] == "fun") name else "get" + name.replaceFirstChar { it.uppercase() }
                }
        }.toSet()
    }

    private fun isInternal(c: Class<*>): Boolean {
        var k: Class<*>? = c
        while (k != null) {
            if (k.simpleName in internalClasses || k.packageName.endsWith(".internal")) return true
            k = k.enclosingClass
        }
        return false
    }

    private fun isPublicClass(c: Class<*>): Boolean {
        var k: Class<*>? = c
        while (k != null) {
            if (!visible(k.modifiers) || k.isSynthetic || k.isAnonymousClass || k.isLocalClass) return false
            k = k.enclosingClass
        }
        return true
    }

    private fun desc(t: Class<*>): String = when {
        t.isArray -> "[" + desc(t.componentType)
        t == Void.TYPE -> "V"
        t == java.lang.Boolean.TYPE -> "Z"
        t == java.lang.Byte.TYPE -> "B"
        t == java.lang.Character.TYPE -> "C"
        t == java.lang.Short.TYPE -> "S"
        t == Integer.TYPE -> "I"
        t == java.lang.Long.TYPE -> "J"
        t == java.lang.Float.TYPE -> "F"
        t == java.lang.Double.TYPE -> "D"
        else -> "L" + t.name.replace('.', '/') + ";"
    }

    private fun mods(m: Int, isInterfaceMember: Boolean = false): String = buildList {
        add(if (Modifier.isPublic(m)) "public" else "protected")
        if (Modifier.isStatic(m)) add("static")
        if (Modifier.isFinal(m)) add("final")
        if (Modifier.isAbstract(m) && !isInterfaceMember) add("abstract")
    }.joinToString(" ")

    private fun dump(): String {
        val loader = Robot::class.java.classLoader
        val out = StringBuilder()
        for (name in classNames()) {
            val c = Class.forName(name, false, loader)
            if (!isPublicClass(c) || isInternal(c)) continue
            val kind = when {
                c.isAnnotation -> "annotation class"
                c.isInterface -> "interface"
                c.isEnum -> "final enum class"
                else -> buildString {
                    if (Modifier.isAbstract(c.modifiers)) append("abstract ")
                    if (Modifier.isFinal(c.modifiers)) append("final ")
                    append("class")
                }
            }
            val supers = listOfNotNull(c.superclass?.takeIf { it != Any::class.java && !c.isEnum })
                .plus(c.interfaces).map { it.name.replace('.', '/') }
            out.append("public ").append(if (Modifier.isStatic(c.modifiers)) "static " else "").append(kind).append(' ')
                .append(name.replace('.', '/'))
            if (supers.isNotEmpty()) out.append(" : ").append(supers.joinToString(", "))
            out.append(" {\n")
            val members = ArrayList<String>()
            c.declaredConstructors.filter { visible(it.modifiers) && !it.isSynthetic && c.simpleName !in internalConstructors }.forEach { k: Constructor<*> ->
                members += "${mods(k.modifiers)} fun <init> (${k.parameterTypes.joinToString("") { desc(it) }})V"
            }
            c.declaredMethods.filter {
                visible(it.modifiers) && !it.isSynthetic && !it.isBridge && '$' !in it.name &&
                    "${c.simpleName}.${it.name}" !in internalTopLevel
            }.forEach { m: Method ->
                members += "${mods(m.modifiers, c.isInterface)} fun ${m.name} (${m.parameterTypes.joinToString("") { desc(it) }})${desc(m.returnType)}"
            }
            c.declaredFields.filter { visible(it.modifiers) && !it.isSynthetic && '$' !in it.name }.forEach { f: Field ->
                members += "${mods(f.modifiers)} field ${f.name} ${desc(f.type)}"
            }
            members.sorted().forEach { out.append('\t').append(it).append('\n') }
            out.append("}\n\n")
        }
        return out.toString()
    }
}
