# passive-fusion services: `docker run passive-fusion <command> ...` runs `pfusion <command>`.
FROM python:3.11-slim
WORKDIR /app
COPY pyproject.toml ./
COPY common ./common
COPY services ./services
COPY scenarios ./scenarios
COPY deploy ./deploy
RUN pip install --no-cache-dir .
ENTRYPOINT ["pfusion"]
