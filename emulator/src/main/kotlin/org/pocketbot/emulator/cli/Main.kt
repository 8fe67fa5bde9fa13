package org.pocketbot.emulator.cli

import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.EmulatorConfig
import org.pocketbot.emulator.SimTime
import org.pocketbot.emulator.Speed
import org.pocketbot.emulator.world.Worlds
import kotlin.system.exitProcess

private const val USAGE = """usage: emulator [--robots N] [--world NAME|FILE.json] [--seed S] [--speed FACTOR|max]
                [--port-base PORT] [--control-port PORT] [--threads N]
  --robots N          robots to start (default 1), ids 1..N, at the world's start poses
  --world W           a shipped world (${'$'}WORLDS) or a world file (default straight)
  --seed S            seed of every random effect (default 1)
  --speed F|max       simulated seconds per wall-clock second (default 1), or max
  --port-base P       robot i listens on 127.0.0.1:P+i-1 (default 40001; 0 = any free port)
  --control-port P    control port listing the robots (default 40000; 0 = any free port, -1 = none)
Runs until stopped (Ctrl-C, or 'q' on stdin). Stdin commands: p pause, r resume, s single step, t time, q quit."""

public fun main(args: Array<String>) {
    var robots = 1
    var world = "straight"
    var seed = 1L
    var speed: Speed = Speed.Realtime(1.0)
    var portBase = 40001
    var controlPort = 40000
    var threads = EmulatorConfig().threads
    var i = 0
    fun value(): String = args.getOrNull(++i) ?: fail("missing value for ${args[i - 1]}")
    while (i < args.size) {
        when (args[i]) {
            "--robots" -> robots = value().toIntOrNull()?.takeIf { it in 1..254 } ?: fail("--robots wants 1..254")
            "--world" -> world = value()
            "--seed" -> seed = value().toLongOrNull() ?: fail("--seed wants a number")
            "--speed" -> speed = value().let { if (it == "max") Speed.AsFastAsPossible else Speed.Realtime(it.toDoubleOrNull()?.takeIf { f -> f > 0 } ?: fail("--speed wants a positive number or max")) }
            "--port-base" -> portBase = value().toIntOrNull() ?: fail("--port-base wants a port")
            "--control-port" -> controlPort = value().toIntOrNull() ?: fail("--control-port wants a port")
            "--threads" -> threads = value().toIntOrNull()?.takeIf { it >= 1 } ?: fail("--threads wants >= 1")
            "-h", "--help" -> { println(USAGE.replace("\$WORLDS", Worlds.names.joinToString())); return }
            else -> fail("unknown argument ${args[i]}")
        }
        i++
    }
    val w = try { Worlds.load(world) } catch (e: IllegalArgumentException) { fail(e.message ?: "bad world") }
    val emu = try {
        Emulator(w, EmulatorConfig(seed = seed, threads = threads)).also { e -> repeat(robots) { e.addRobot() } }
    } catch (e: IllegalStateException) { fail(e.message ?: "cannot start") }
    val control = emu.startTcp(basePort = portBase, controlPort = controlPort)
    println("PocketBot emulator: world ${w.name}, ${robots} robot(s), seed $seed, speed ${describe(speed)}")
    for (r in emu.robots) println("robot ${r.id} ${r.name} tcp 127.0.0.1:${r.tcpPort}")
    if (control >= 0) println("control 127.0.0.1:$control")
    System.out.flush()
    Runtime.getRuntime().addShutdownHook(Thread { emu.close() })
    emu.start(speed)
    val input = System.`in`.bufferedReader()
    while (true) {
        val line = try { input.readLine() } catch (_: Exception) { null }
        if (line == null) { Thread.sleep(Long.MAX_VALUE); continue } // no stdin (e.g. in the background): run until killed
        when (line.trim()) {
            "p" -> { emu.pause(); println("paused at ${emu.time}") }
            "r" -> { emu.resume(); println("running") }
            "s" -> { emu.pause(); emu.singleStep(); println("t=${emu.time}") }
            "t" -> println("t=${emu.time} (${emu.timeTicks} ticks of ${SimTime.TICKS_PER_SECOND} Hz)")
            "q" -> { emu.close(); exitProcess(0) }
            "" -> {}
            else -> println("commands: p pause, r resume, s single step, t time, q quit")
        }
    }
}

private fun describe(s: Speed) = when (s) {
    Speed.AsFastAsPossible -> "max"
    is Speed.Realtime -> "x${s.factor}"
}

private fun fail(msg: String): Nothing {
    System.err.println("emulator: $msg")
    System.err.println(USAGE.replace("\$WORLDS", Worlds.names.joinToString()))
    exitProcess(2)
}
