package org.pocketbot.emulator.world

import java.nio.file.Files
import java.nio.file.Path
import java.nio.file.Paths

/**
 * The worlds shipped in emulator/worlds (also on the class path under `worlds/`), and loading of world files.
 */
public object Worlds {
    /** Names of the shipped worlds. */
    public val names: List<String> = listOf("straight", "round", "figure-eight", "fork", "colours", "box", "push", "track", "open")

    /**
     * The world called [nameOrPath]: a shipped world's name, or a path to a JSON world file.
     * Throws [IllegalArgumentException] when there is none.
     */
    public fun load(nameOrPath: String): World {
        val file = Paths.get(nameOrPath)
        if (nameOrPath.endsWith(".json") && Files.isRegularFile(file)) return World.fromJson(Files.readString(file))
        val res = Worlds::class.java.getResourceAsStream("/worlds/$nameOrPath.json")
            ?: throw IllegalArgumentException("no world '$nameOrPath' (shipped: ${names.joinToString()})")
        return res.use { World.fromJson(it.readBytes().toString(Charsets.UTF_8)) }
    }

    public fun save(world: World, path: Path) { Files.writeString(path, world.toJson()) }
}
